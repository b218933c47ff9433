//! Requests of the shared image service: `inspect` (size, palette,
//! clusters, thumbnail; `filigree inspect`) and `decode-image` (RGBA pixels).
use super::RawImage;
use crate::core::error::{Error, Result};
use crate::core::job::{Job, OneShot, Progress, Step};
use crate::core::request_limits as lim;
use crate::inspect::{InspectJob, InspectOptions, Inspection};
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

/// `inspect` as a job: decoding is the first step (one call of the
/// decoder), then [`InspectJob`] in bounded steps.
pub struct InspectRequestJob {
    bytes: Option<Vec<u8>>,
    opts: InspectOptions,
    job: Option<InspectJob>,
}

impl Job for InspectRequestJob {
    type Output = InspectResponse;
    fn step(&mut self) -> Result<Step<InspectResponse>> {
        if let Some(bytes) = self.bytes.take() {
            let img = decode(&bytes, self.opts.limits).map_err(|e| e.at("bytes"))?;
            drop(bytes);
            self.job = Some(InspectJob::new(img, &self.opts)?);
            return Ok(Step::Running(Progress::new(0.05, "reading pixels")));
        }
        let job = self
            .job
            .as_mut()
            .ok_or_else(|| Error::input("this job has already finished"))?;
        Ok(match job.step()? {
            Step::Running(p) => Step::Running(Progress::new(0.05 + 0.95 * p.fraction, p.stage)),
            Step::Done(info) => {
                self.job = None;
                let thumbnail = RawImage::from(info.thumbnail.clone());
                Step::Done(InspectResponse { info, thumbnail })
            }
        })
    }
}

/// Check an `inspect` request and start it.
pub fn start_inspect(req: InspectRequest) -> Result<InspectRequestJob> {
    let opts = InspectOptions {
        tolerance: lim::finite_in("tolerance", req.tolerance, lim::TOLERANCE)?,
        ..Default::default()
    };
    Ok(InspectRequestJob {
        bytes: Some(req.bytes),
        opts,
        job: None,
    })
}

/// Start a `decode-image` request.
pub fn start_decode(req: DecodeImageRequest) -> impl Job<Output = RawImage> {
    OneShot::new(move || {
        decode(&req.bytes, Limits::default())
            .map(RawImage::from)
            .map_err(|e| e.at("bytes"))
    })
}
