//! Every size and work limit of the core, in one place.
//!
//! Each limit exists so that no input — a file, a program, a request from
//! the page — can make the core allocate without bound, loop for ever or
//! overflow a stack. The figures are chosen for the weakest target: a
//! browser tab running the wasm build, where `usize` is 32 bits, memory is
//! at most 4 GiB and the stack is about 1 MiB.
//!
//! Rules for limits:
//! - a limit is a named constant here, documented with what it bounds and why
//!   its value;
//! - a check happens *before* the allocation or the work it bounds, with
//!   arithmetic in `u64` (or checked), so it cannot wrap on 32 bits;
//! - the error is [`crate::core::error::Error::Limit`] and its message names
//!   the limit in words and gives its value (e.g. "exceeds the 4096×4096
//!   limit", "at most 200000 stroke points").
//!
//! Tools do not invent their own magic numbers; they refer to these.

// ---------------------------------------------------------------- images --

/// Largest width and largest height of any image the core decodes or
/// receives as raw pixels (sources, masks, targets, element sheets).
pub const MAX_IMAGE_SIDE: u32 = 4096;

/// Largest pixel count (width × height) of any image: 16 Mpx, that is 64 MiB
/// of RGBA, which a browser tab can hold a few times over while a tool
/// works on copies.
pub const MAX_IMAGE_PIXELS: u64 = MAX_IMAGE_SIDE as u64 * MAX_IMAGE_SIDE as u64;

/// Largest single allocation the image decoders may make while decoding
/// (e.g. a 16-bit 4096² PNG needs 128 MiB before conversion to 8-bit RGBA).
pub const MAX_DECODE_ALLOC: u64 = 512 * 1024 * 1024;

/// Largest longer side of a thumbnail (the inspect answer's preview).
pub const MAX_THUMBNAIL_SIDE: u32 = 1024;

/// The number of bytes of an RGBA image of `width` × `height`, or `None`
/// when that does not fit in `usize` on this platform (on wasm32 a
/// 65536×65536 image would wrap to 0 bytes).
pub fn rgba_bytes(width: u32, height: u32) -> Option<usize> {
    let n = (width as u64).checked_mul(height as u64)?.checked_mul(4)?;
    usize::try_from(n).ok()
}

// --------------------------------------------------------------- inspect --

/// Largest clustering tolerance (RGB Euclidean distance). The diagonal of
/// the RGB cube is √3·255 ≈ 441.7, so 442 already merges every colour.
pub const MAX_TOLERANCE: f64 = 442.0;

/// At most this many colour clusters are listed in an inspect answer; the
/// total is always counted exactly (`cluster_count`).
pub const MAX_LISTED_CLUSTERS: usize = 1024;

/// At most this many exact colours are listed in an inspect answer by
/// default; the total is always counted exactly (`colour_count`).
pub const MAX_LISTED_COLOURS: usize = 256;

// ----------------------------------------------------------------- pixel --

/// Largest element cell side, in pixels. Elements are "very small pixel art
/// images"; this keeps a mistaken full-size picture from being placed as one
/// element (the placement cost grows with side²).
pub const MAX_ELEMENT_SIDE: u32 = 256;

/// Largest absolute element margin, in pixels. A margin wider than the
/// largest image can do nothing more, and keeping margins this small keeps
/// every position sum far inside `i32`.
pub const MAX_MARGIN: i32 = MAX_IMAGE_SIDE as i32;

/// Largest source palette the colour-difference and shared-border colour
/// maps accept: their cost grows with the square of the colour count, and
/// pixel-art palettes are small. (The HSV shift has no such limit.)
pub const MAX_PALETTE: usize = 4096;

/// Largest annotation upscale factor K (strokes are rasterised on a K× grid).
pub const MAX_ANNOTATION_SCALE: u32 = 32;

/// Largest number of stroke points over all strokes of one request.
pub const MAX_STROKE_POINTS: usize = 200_000;

/// Largest total length of the strokes rasterised on the K× annotation grid,
/// in grid pixels (checked from the points before rasterising): about 60
/// strokes right across a 4096-pixel image at K = 4.
pub const MAX_ANNOTATION_PATH: u64 = 1 << 20;

/// Largest grid the orientation (Laplace) solve runs on. Bigger sources are
/// solved on a grid reduced by a whole factor to at most this many pixels
/// (annotations averaged into it) and the field is interpolated back, with
/// every annotated pixel keeping its own vector exactly: the solve's cost
/// stays bounded (a few hundred ms) while an element, which takes the mean
/// direction over its cell snapped to eight directions, sees the same field.
/// Sources up to 512² are solved at full resolution.
pub const MAX_SOLVE_PIXELS: usize = 512 * 512;

/// Safety cap on conjugate-gradient iterations per component of the
/// orientation (Laplace) solve; the multigrid preconditioner converges in
/// a few dozen.
pub const MAX_SOLVER_ITERATIONS: usize = 500;

// ------------------------------------------------------ pattern language --

/// Largest accepted program text, in bytes.
pub const MAX_PROGRAM_BYTES: usize = 256 * 1024;

/// Interpreter operations per recording (each statement and expression node
/// counts one): a few milliseconds of work.
pub const MAX_PROGRAM_OPS: u64 = 1_000_000;

/// Shapes one recording may emit; every primitive counts, inside paths and
/// boolean blocks too (a cubic is 8 quadratic pieces).
pub const MAX_SHAPES: usize = 5_000;

/// One nesting budget for parsing and recording (blocks, parentheses,
/// operator chains, expression nodes and function calls, added up through
/// every active call), chosen to fit the wasm stack with a safety factor of
/// at least 3 for every kind of nesting; the measurements are in
/// `src/pattern/lang.rs` (`MAX_DEPTH`) and `tests/e2e/pattern-depth.test.mjs`.
pub const MAX_NESTING: usize = 160;

/// Largest side of a pattern render including supersampling
/// (size × samples per side).
pub const MAX_RENDER_SIDE: usize = 4096;

// ------------------------------------------------ project files, states --

/// Largest project file (`open-project` text), in bytes: a Pixel project
/// with a 4096² mask (21 MiB of base64), its source, sheet and 200,000
/// stroke points fits with room to spare.
pub const MAX_PROJECT_BYTES: usize = 128 * 1024 * 1024;

/// Most values (numbers, texts, lists, objects, byte strings) in one tool
/// state or project file: 200,000 stroke points take 600,000.
pub const MAX_STATE_VALUES: usize = 2_000_000;

/// Deepest nesting of lists and objects in a tool state or project file
/// (a real state is 5 deep).
pub const MAX_STATE_DEPTH: usize = 64;

// -------------------------------------------------------------- requests --
// The ranges of the numbers a person types or a panel sends (tolerance,
// render size, GA population, shards, Pixel margins, ...) are the other half
// of this list: [`crate::core::request_limits`], beside the checks that
// apply them where a request enters the core.

// ----------------------------------------------------------------- micro --

/// Micro scenes: most nodes in one scene tree, deepest nesting, most
/// children of one boolean, bytes of scene JSON (so a scene cannot make
/// evaluation slow without bound or its parse overflow a stack).
pub const MAX_MICRO_NODES: usize = 256;
pub const MAX_MICRO_DEPTH: usize = 24;
pub const MAX_MICRO_CHILDREN: usize = 64;
pub const MAX_MICRO_SCENE_BYTES: usize = 256 * 1024;
/// Micro: terms of a periodic sum, monomials of a polynomial, congruences
/// of a selection, shapes of a particle mixture.
pub const MAX_MICRO_TERMS: usize = 64;
/// Micro renders and slices: largest side and pixel count (4 Mpx).
pub const MAX_MICRO_SIDE: u32 = 2048;
pub const MAX_MICRO_PIXELS: u64 = 4 * 1024 * 1024;
/// Micro sphere tracing: most steps along one ray.
pub const MAX_MICRO_STEPS: u32 = 20_000;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rgba_bytes_never_wraps() {
        assert_eq!(rgba_bytes(3, 2), Some(24));
        assert_eq!(rgba_bytes(0, 5), Some(0));
        // 65536² × 4 = 2^34: more than a 32-bit usize holds. Computed in
        // u64 it is exact; it must never come back as a wrapped small number.
        let big = rgba_bytes(65536, 65536);
        if usize::BITS == 32 {
            assert_eq!(big, None);
        } else {
            assert_eq!(big, Some(1usize << 34));
        }
        let huge = rgba_bytes(u32::MAX, u32::MAX);
        let want = (u32::MAX as u128) * (u32::MAX as u128) * 4;
        assert!(huge.is_none() || huge.map(|n| n as u128) == Some(want));
    }

    #[test]
    fn image_limit_fits_every_platform() {
        // The largest accepted image must be addressable on wasm32.
        let bytes = MAX_IMAGE_PIXELS * 4;
        assert!(bytes <= u32::MAX as u64);
        assert_eq!(
            rgba_bytes(MAX_IMAGE_SIDE, MAX_IMAGE_SIDE),
            Some(bytes as usize)
        );
        assert!(MAX_TOLERANCE >= (3.0f64).sqrt() * 255.0);
    }
}
