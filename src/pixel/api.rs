//! Pixel's requests as typed data, shared by `filigree pixel` and the
//! browser worker (`pixel`, `pixel-mask`). Defaults are defined once: the
//! request's `Default` (and [`PixelParams`]'s); every error names the field
//! at fault ([`Error::at`]): `source`, `mask`, `sheet`, `sprite`,
//! `strokes`, `params.<name>`.
use super::{inputs, orientation, ElementSheet, Elements, PixelJob, PixelParams, Stroke};
use crate::core::error::{Error, Result};
use crate::core::job::{Job, OneShot};
use crate::core::request_limits as lim;
use crate::raster::{decode, Limits, Rgba8Image};
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

/// Decode a mask image into bits.
pub fn mask_bits(req: &PixelMaskRequest) -> Result<MaskBits> {
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

/// Check every numeric setting where it enters; errors name `params.<field>`.
pub fn check_params(p: &PixelParams) -> Result<()> {
    lim::int_in(
        "params.annotation_scale",
        p.annotation_scale,
        lim::ANNOTATION_SCALE,
    )?;
    lim::finite_in("params.density", p.density, (0.0, 1.0))?;
    for (i, m) in p.margins.iter().enumerate() {
        lim::int_in(
            &format!("params.margins.{i}"),
            *m,
            (-lim::MARGIN, lim::MARGIN),
        )?;
    }
    lim::finite_in("params.hsv.0", p.hsv[0], (-lim::HUE_SHIFT, lim::HUE_SHIFT))?;
    lim::finite_in("params.hsv.1", p.hsv[1], (-lim::SV_SHIFT, lim::SV_SHIFT))?;
    lim::finite_in("params.hsv.2", p.hsv[2], (-lim::SV_SHIFT, lim::SV_SHIFT))?;
    lim::finite_in("params.d_max", p.d_max, lim::D_MAX)?;
    Ok(())
}

/// Check a `pixel` request and start its job.
pub fn start_pixel(req: PixelRequest) -> Result<PixelJob> {
    check_params(&req.params)?;
    let source = decode(&req.source, Limits::default()).map_err(|e| e.at("source"))?;
    // The mask's bits are what `to_image` + `mask_from_image` give (inside
    // = non-zero); the checks that read every pixel run in the job's steps.
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
    if (source.width, source.height) != (m.width, m.height) {
        return Err(Error::input(format!(
            "the mask is {}×{} pixels but the source image is {}×{}; they must be the same size",
            m.width, m.height, source.width, source.height
        ))
        .at("mask"));
    }
    let mask: Vec<bool> = m.bits.iter().map(|&b| b != 0).collect();
    let elements = match (req.sheet, req.sprite) {
        (Some(b), None) => {
            let img = decode(&b, Limits::default()).map_err(|e| e.at("sheet"))?;
            ElementSheet::from_sheet(&img).map_err(|e| e.at("sheet"))?;
            Elements::Sheet(img)
        }
        (None, Some(b)) => {
            let img = decode(&b, Limits::default()).map_err(|e| e.at("sprite"))?;
            ElementSheet::from_sprite(&img, req.params.sprite_direction)
                .map_err(|e| e.at("sprite"))?;
            Elements::Sprite(img)
        }
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
    orientation::check_strokes(source.width, source.height, &req.strokes)
        .map_err(|e| e.at("strokes"))?;
    PixelJob::start(source, mask, elements, req.strokes, req.params).map_err(|e| {
        if e.field().is_some() {
            e
        } else {
            e.at("params")
        }
    })
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
