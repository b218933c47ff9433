//! Requests of the shared image service: `inspect` (size, palette,
//! clusters, thumbnail; `filigree inspect`) and `decode-image` (RGBA pixels).
use super::RawImage;
use crate::core::error::Result;
use crate::core::job::{Job, OneShot};
use crate::core::request_limits as lim;
use crate::inspect::{inspect, InspectOptions, Inspection};
use crate::raster::{decode, Limits};
use serde::{Deserialize, Serialize};

/// `inspect` / `filigree inspect`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct InspectRequest {
    /// The image file (PNG, JPEG, WebP, GIF, BMP).
    #[serde(with = "serde_bytes")]
    pub bytes: Vec<u8>,
    /// RGB distance under which colours are merged into one cluster, 0..=442 (24).
    pub tolerance: f64,
}

impl Default for InspectRequest {
    fn default() -> Self {
        InspectRequest {
            bytes: vec![],
            tolerance: InspectOptions::default().tolerance,
        }
    }
}

/// What `inspect` answers: the [`Inspection`] and its thumbnail's pixels.
#[derive(Debug, Clone, Serialize)]
pub struct InspectResponse {
    #[serde(flatten)]
    pub info: Inspection,
    pub thumbnail: RawImage,
}

/// `decode-image`: an image file → RGBA pixels.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DecodeImageRequest {
    #[serde(with = "serde_bytes")]
    pub bytes: Vec<u8>,
}

/// Check an `inspect` request and start it.
pub fn start_inspect(req: InspectRequest) -> Result<impl Job<Output = InspectResponse>> {
    let opts = InspectOptions {
        tolerance: lim::finite_in("tolerance", req.tolerance, lim::TOLERANCE)?,
        ..Default::default()
    };
    Ok(OneShot::new(move || {
        let info = inspect(&req.bytes, &opts).map_err(|e| e.at("bytes"))?;
        let thumbnail = RawImage::from(info.thumbnail.clone());
        Ok(InspectResponse { info, thumbnail })
    }))
}

/// Start a `decode-image` request.
pub fn start_decode(req: DecodeImageRequest) -> impl Job<Output = RawImage> {
    OneShot::new(move || {
        decode(&req.bytes, Limits::default())
            .map(RawImage::from)
            .map_err(|e| e.at("bytes"))
    })
}
