//! Requests of the shared image service: `inspect` (size, palette,
//! clusters, thumbnail; `filigree inspect`) and `decode-image` (RGBA pixels).
use super::RawImage;
use crate::core::error::{Error, Result};
use crate::core::job::{Job, Progress, Step};
use crate::core::request_limits as lim;
use crate::inspect::{InspectJob, InspectOptions, Inspection};
use crate::raster::{decode, Decoder, Decoding, Limits, DECODE_PIXELS_PER_STEP};
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

/// `inspect` as a job: decoding first (a PNG a few rows a step, see
/// [`Decoding`]), then [`InspectJob`] in bounded steps.
pub struct InspectRequestJob {
    decoding: Option<Decoding>,
    opts: InspectOptions,
    job: Option<InspectJob>,
}

impl Job for InspectRequestJob {
    type Output = InspectResponse;
    fn step(&mut self) -> Result<Step<InspectResponse>> {
        if let Some(d) = &mut self.decoding {
            let Some(img) = d.step(DECODE_PIXELS_PER_STEP).map_err(|e| e.at("bytes"))? else {
                let f = 0.05 * d.fraction();
                return Ok(Step::Running(Progress::new(f, "reading pixels")));
            };
            self.decoding = None;
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

/// Check an `inspect` request and start it (any format: the user's file).
pub fn start_inspect(req: InspectRequest) -> Result<InspectRequestJob> {
    start_inspect_with(req, decode)
}

/// [`start_inspect`], decoding what is not read in parts with `whole`
/// (see [`Decoding::with`]).
pub fn start_inspect_with(req: InspectRequest, whole: Decoder) -> Result<InspectRequestJob> {
    let opts = InspectOptions {
        tolerance: lim::finite_in("tolerance", req.tolerance, lim::TOLERANCE)?,
        ..Default::default()
    };
    Ok(InspectRequestJob {
        decoding: Some(Decoding::with(req.bytes, opts.limits, whole)),
        opts,
        job: None,
    })
}

/// Start a `decode-image` request (a PNG a few rows a step, see
/// [`Decoding`]; any format).
pub fn start_decode(req: DecodeImageRequest) -> impl Job<Output = RawImage> {
    start_decode_with(req, decode)
}

/// [`start_decode`], decoding what is not read in parts with `whole`
/// (see [`Decoding::with`]).
pub fn start_decode_with(req: DecodeImageRequest, whole: Decoder) -> impl Job<Output = RawImage> {
    DecodeJob(Decoding::with(req.bytes, Limits::default(), whole))
}

/// `decode-image` as a job.
struct DecodeJob(Decoding);

impl Job for DecodeJob {
    type Output = RawImage;
    fn step(&mut self) -> Result<Step<RawImage>> {
        Ok(
            match self
                .0
                .step(DECODE_PIXELS_PER_STEP)
                .map_err(|e| e.at("bytes"))?
            {
                Some(img) => Step::Done(RawImage::from(img)),
                None => Step::Running(Progress::new(self.0.fraction(), "reading pixels")),
            },
        )
    }
}
