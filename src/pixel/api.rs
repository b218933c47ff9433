//! Pixel's requests as typed data, shared by `filigree pixel` and the
//! browser worker (`pixel`, `pixel-mask`). Defaults are defined once: the
//! request's `Default` (and [`PixelParams`]'s); every error names the field
//! at fault ([`Error::at`]): `source`, `mask`, `sheet`, `sprite`,
//! `strokes`, `params.<name>`.
use super::{
    inputs, orientation, ElementSheet, Elements, PixelJob, PixelOutput, PixelParams, Stroke,
};
use crate::core::error::{Error, Result};
use crate::core::job::{Job, OneShot, Progress, Step};
use crate::core::request_limits as lim;
use crate::raster::{decode_sent, Decoder, Decoding, Limits, Rgba8Image, DECODE_PIXELS_PER_STEP};
use serde::{Deserialize, Serialize};

/// A mask as the browser edits it: one byte per pixel, non-zero = textured.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MaskBits {
    pub width: u32,
    pub height: u32,
    #[serde(with = "serde_bytes")]
    pub bits: Vec<u8>,
}

impl MaskBits {
    /// The inside of a mask image (see [`inputs::mask_from_image`]).
    pub fn of_image(img: &Rgba8Image) -> MaskBits {
        MaskBits {
            width: img.width,
            height: img.height,
            bits: inputs::mask_from_image(img)
                .into_iter()
                .map(u8::from)
                .collect(),
        }
    }

    /// The mask as an image that [`inputs::mask_from_image`] reads back
    /// exactly: opaque white inside, transparent outside.
    pub fn to_image(&self) -> Result<Rgba8Image> {
        let want = self.width as u64 * self.height as u64;
        if self.bits.len() as u64 != want {
            return Err(Error::input(format!(
                "the mask has {} values but is declared {}×{}",
                self.bits.len(),
                self.width,
                self.height
            )));
        }
        let data = self
            .bits
            .iter()
            .flat_map(|&b| if b != 0 { [255; 4] } else { [0; 4] })
            .collect();
        Rgba8Image::from_raw(self.width, self.height, data)
    }
}

/// `pixel-mask`: a mask image file → bits.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PixelMaskRequest {
    /// The mask image file (PNG, ...).
    #[serde(with = "serde_bytes")]
    pub bytes: Vec<u8>,
}

/// Decode a mask image into bits (every format natively, PNG only in wasm:
/// [`decode_sent`]).
pub fn mask_bits(req: &PixelMaskRequest) -> Result<MaskBits> {
    mask_bits_with(req, decode_sent)
}

/// [`mask_bits`] decoding with `decode`.
pub fn mask_bits_with(req: &PixelMaskRequest, decode: Decoder) -> Result<MaskBits> {
    let img = decode(&req.bytes, Limits::default()).map_err(|e| e.at("bytes"))?;
    Ok(MaskBits::of_image(&img))
}

/// Start a `pixel-mask` request (one step: a decode).
pub fn start_mask(req: PixelMaskRequest) -> impl Job<Output = MaskBits> {
    OneShot::new(move || mask_bits(&req))
}

/// `pixel` / `filigree pixel`. Images are encoded files (PNG, ...); the mask
/// is bits (a mask file becomes bits through `pixel-mask`); exactly one of
/// `sheet` and `sprite` is given.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PixelRequest {
    /// The pixel art to texture.
    #[serde(with = "serde_bytes")]
    pub source: Vec<u8>,
    pub mask: MaskBits,
    /// A 3×3 element sheet.
    #[serde(with = "serde_bytes", skip_serializing_if = "Option::is_none")]
    pub sheet: Option<Vec<u8>>,
    /// Or one sprite, turned eight ways.
    #[serde(with = "serde_bytes", skip_serializing_if = "Option::is_none")]
    pub sprite: Option<Vec<u8>>,
    /// Brush strokes in source pixels; may be empty.
    pub strokes: Vec<Stroke>,
    pub params: PixelParams,
}

/// The range of one setting: a number, or a whole number.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Range {
    Number(f64, (f64, f64)),
    Whole(i64, (i64, i64)),
}

/// Every ranged setting of `p` with its field (`<name>`, an item of a list
/// `<name>.<i>`, within `params`), its value and its range: the one list that
/// the request's check ([`check_params`]) and the document's
/// ([`super::state`]) read, each in its own words.
pub fn ranges(p: &PixelParams) -> [(&'static str, Range); 8] {
    use Range::{Number, Whole};
    let (m, hue, sv) = (lim::MARGIN as i64, lim::HUE_SHIFT, lim::SV_SHIFT);
    let k = lim::ANNOTATION_SCALE;
    [
        (
            "annotation_scale",
            Whole(p.annotation_scale.into(), (k.0.into(), k.1.into())),
        ),
        ("density", Number(p.density, lim::DENSITY)),
        ("margins.0", Whole(p.margins[0].into(), (-m, m))),
        ("margins.1", Whole(p.margins[1].into(), (-m, m))),
        ("hsv.0", Number(p.hsv[0], (-hue, hue))),
        ("hsv.1", Number(p.hsv[1], (-sv, sv))),
        ("hsv.2", Number(p.hsv[2], (-sv, sv))),
        ("d_max", Number(p.d_max, lim::D_MAX)),
    ]
}

/// Check every numeric setting where it enters; errors name `params.<field>`.
pub fn check_params(p: &PixelParams) -> Result<()> {
    for (field, range) in ranges(p) {
        let field = format!("params.{field}");
        match range {
            Range::Number(v, r) => lim::finite_in(&field, v, r).map(drop)?,
            Range::Whole(v, r) => lim::int_in(&field, v, r).map(drop)?,
        }
    }
    if p.exclude.len() > lim::EXCLUDED {
        return Err(Error::input(format!(
            "`params.exclude` must hold at most {} colours (got {})",
            lim::EXCLUDED,
            p.exclude.len()
        ))
        .at("params.exclude"));
    }
    Ok(())
}

/// Check a `pixel` request and start its job. Only the cheap checks run
/// here; the images are decoded in the job's first steps (a PNG a few rows
/// a step, see [`Decoding`]) and the checks that need their pixels follow,
/// with the same errors and fields. The images are read as
/// [`decode_sent`] reads: every format natively (the CLI reads the user's
/// files), PNG only in wasm (the page sends PNG, so the Pixel module links
/// no other decoder).
pub fn start_pixel(req: PixelRequest) -> Result<PixelRequestJob> {
    start_pixel_with(req, decode_sent)
}

/// [`start_pixel`], with `whole` decoding what a [`Decoding`] does not read
/// in parts ([`Decoding::with`]; [`decode_sent`] for [`start_pixel`]).
pub fn start_pixel_with(req: PixelRequest, whole: Decoder) -> Result<PixelRequestJob> {
    check_params(&req.params)?;
    let m = &req.mask;
    if m.bits.len() as u64 != m.width as u64 * m.height as u64 {
        return Err(Error::input(format!(
            "the mask has {} values but is declared {}×{}",
            m.bits.len(),
            m.width,
            m.height
        ))
        .at("mask"));
    }
    let (elements, sprite) = match (req.sheet, req.sprite) {
        (Some(b), None) => (b, false),
        (None, Some(b)) => (b, true),
        (Some(_), Some(_)) => {
            return Err(
                Error::input("give either an element sheet or a single sprite, not both")
                    .at("sprite"),
            )
        }
        (None, None) => {
            return Err(
                Error::input("an element sheet (3×3) or a single sprite is needed").at("sheet"),
            )
        }
    };
    Ok(PixelRequestJob {
        reading: Some(Reading {
            source: Decoding::with(req.source, Limits::default(), whole),
            source_img: None,
            elements: Decoding::with(elements, Limits::default(), whole),
            sprite,
            mask: req.mask,
            strokes: req.strokes,
            params: req.params,
        }),
        job: None,
    })
}

/// A `pixel` request as a job: its images decoded in bounded steps, then
/// the [`PixelJob`].
pub struct PixelRequestJob {
    reading: Option<Reading>,
    job: Option<PixelJob>,
}

/// What a `pixel` request holds while its images are being decoded.
struct Reading {
    source: Decoding,
    source_img: Option<Rgba8Image>,
    /// The element sheet or the sprite.
    elements: Decoding,
    sprite: bool,
    mask: MaskBits,
    strokes: Vec<Stroke>,
    params: PixelParams,
}

/// Share of a `pixel` job's progress spent decoding its images.
const READING: f64 = 0.05;

impl Reading {
    /// Decode a bounded part more; the started [`PixelJob`] once both
    /// images are read and checked.
    fn step(&mut self) -> Result<Option<PixelJob>> {
        if self.source_img.is_none() {
            self.source_img = self
                .source
                .step(DECODE_PIXELS_PER_STEP)
                .map_err(|e| e.at("source"))?;
            return Ok(None);
        }
        let field = if self.sprite { "sprite" } else { "sheet" };
        let Some(img) = self
            .elements
            .step(DECODE_PIXELS_PER_STEP)
            .map_err(|e| e.at(field))?
        else {
            return Ok(None);
        };
        let source = self.source_img.take().expect("decoded above");
        let m = &self.mask;
        if (source.width, source.height) != (m.width, m.height) {
            return Err(Error::input(format!(
                "the mask is {}×{} pixels but the source image is {}×{}; they must be the same size",
                m.width, m.height, source.width, source.height
            ))
            .at("mask"));
        }
        let elements = if self.sprite {
            ElementSheet::from_sprite(&img, self.params.sprite_direction)
                .map_err(|e| e.at(field))?;
            Elements::Sprite(img)
        } else {
            ElementSheet::from_sheet(&img).map_err(|e| e.at(field))?;
            Elements::Sheet(img)
        };
        orientation::check_strokes(source.width, source.height, &self.strokes)
            .map_err(|e| e.at("strokes"))?;
        let mask: Vec<bool> = std::mem::take(&mut self.mask.bits)
            .into_iter()
            .map(|b| b != 0)
            .collect();
        let strokes = std::mem::take(&mut self.strokes);
        let params = self.params.clone();
        PixelJob::start(source, mask, elements, strokes, params)
            .map(Some)
            .map_err(|e| {
                if e.field().is_some() {
                    e
                } else {
                    e.at("params")
                }
            })
    }

    fn fraction(&self) -> f64 {
        if self.source_img.is_none() {
            0.8 * self.source.fraction()
        } else {
            0.8 + 0.2 * self.elements.fraction()
        }
    }
}

impl Job for PixelRequestJob {
    type Output = PixelOutput;
    fn step(&mut self) -> Result<Step<PixelOutput>> {
        if let Some(r) = &mut self.reading {
            let started = r.step()?;
            let f = READING * r.fraction();
            if let Some(job) = started {
                self.reading = None;
                self.job = Some(job);
                return Ok(Step::Running(Progress::new(READING, "checking the inputs")));
            }
            return Ok(Step::Running(Progress::new(f, "reading pixels")));
        }
        let job = self
            .job
            .as_mut()
            .ok_or_else(|| Error::input("this job has already finished"))?;
        Ok(match job.step()? {
            Step::Running(p) => Step::Running(Progress::new(
                READING + (1.0 - READING) * p.fraction,
                p.stage,
            )),
            Step::Done(out) => {
                self.job = None;
                Step::Done(out)
            }
        })
    }
}

/// The result of a `pixel` job. `field` has `2·width·height` numbers (x, y
/// per pixel, row-major, y down).
#[derive(Debug, Clone, Serialize)]
pub struct PixelResponse {
    pub width: u32,
    pub height: u32,
    #[serde(with = "serde_bytes")]
    pub rgba: Vec<u8>,
    #[serde(with = "serde_bytes")]
    pub colour_map: Vec<u8>,
    pub field: Vec<f32>,
    pub positions: Vec<(i32, i32)>,
    pub placed: usize,
    pub colours_before: usize,
    pub colours_after: usize,
    pub colour_map_used: &'static str,
    pub stats: super::PixelStats,
}

impl From<super::PixelOutput> for PixelResponse {
    fn from(out: super::PixelOutput) -> Self {
        let s = out.stats;
        PixelResponse {
            width: out.image.width,
            height: out.image.height,
            rgba: out.image.data,
            colour_map: out.colour_map.data,
            field: out.field.iter().flat_map(|v| [v[0], v[1]]).collect(),
            positions: out.positions,
            placed: s.placed,
            colours_before: s.colours_before,
            colours_after: s.colours_after,
            colour_map_used: s.colour_map_used.name(),
            stats: s,
        }
    }
}

/// The decoded images of a response, for callers that want pixels back.
impl PixelResponse {
    pub fn image(&self) -> Result<Rgba8Image> {
        Rgba8Image::from_raw(self.width, self.height, self.rgba.clone())
    }
}
