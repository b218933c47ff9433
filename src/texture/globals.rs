//! Global values of an image that the model classifier reads beside the
//! PCN-2 histograms (our addition; not in the paper).
//!
//! PCN-2's features are histograms of binary codes of small filter
//! responses: they say which local shapes occur, not at what size nor how
//! strongly. Several model pairs differ mostly there (cellular walls vs
//! the cellular-dominated fusion, the foldings' ridge spacing, the
//! scattered textons' density), so the classifier also reads 28 global
//! values of what the network reads (the `side × side` view):
//!
//! - the 12 raw perceptual-scale measures ([`scales::measure`], before
//!   the quantiles);
//! - the share of the spectrum's power in 13 radial frequency bands
//!   (about half an octave each, from 1 to 64 cycles per view), as
//!   log₁₀(share + 10⁻⁶);
//! - the grey levels' standard deviation, skewness and log kurtosis.
//!
//! The index standardises them with the training images' means and
//! standard deviations ([`super::index::GlobalScaler`]). Chosen on a
//! validation split of the training bases, never the test set
//! (`src/bench/examples/texture_tta.rs`, `docs/bench/texture-accuracy-2026-12-03.md`).
//! `libm` and the crate's FFT: the same bits natively and in wasm.
use super::scales;
use super::Gray;
use crate::core::error::{Error, Result};

/// How many global values [`measure`] returns.
pub const GLOBALS: usize = 28;

/// Upper edges of the radial bands (cycles per view); the first band
/// starts at 0.5 (the DC term is left out).
const BAND_EDGES: [f64; 14] = [
    0.5, 1.5, 2.5, 3.5, 5.0, 7.0, 10.0, 14.0, 20.0, 28.0, 40.0, 56.0, 80.0, 200.0,
];

/// The global values of a square view whose side is a power of two
/// (the network's view, 128² for the shipped index).
pub fn measure(view: &Gray) -> Result<Vec<f32>> {
    let n = view.width;
    if view.height != n || !n.is_power_of_two() || view.data.len() != n * n {
        return Err(Error::input(format!(
            "global texture values need a square power-of-two view, not {}×{}",
            view.width, view.height
        )));
    }
    let mut out: Vec<f32> = scales::measure(view)?.iter().map(|&x| x as f32).collect();
    let count = (n * n) as f64;
    let mean = view.data.iter().map(|&x| x as f64).sum::<f64>() / count;
    let mut re: Vec<f32> = view
        .data
        .iter()
        .map(|&x| (x as f64 - mean) as f32)
        .collect();
    let mut im = vec![0f32; n * n];
    crate::geom::fft::fft2(&mut re, &mut im, n, n, false)?;
    let mut band = [0f64; BAND_EDGES.len() - 1];
    let mut total = 0.0;
    let signed = |i: usize| {
        if i < n / 2 {
            i as f64
        } else {
            i as f64 - n as f64
        }
    };
    for y in 0..n {
        for x in 0..n {
            let r = (signed(x) * signed(x) + signed(y) * signed(y)).sqrt();
            let p = (re[y * n + x] as f64).powi(2) + (im[y * n + x] as f64).powi(2);
            total += p;
            if let Some(b) = (0..band.len()).find(|&b| r >= BAND_EDGES[b] && r < BAND_EDGES[b + 1])
            {
                band[b] += p;
            }
        }
    }
    out.extend(
        band.iter()
            .map(|&b| libm::log10(b / total.max(1e-12) + 1e-6) as f32),
    );
    let sd = (view
        .data
        .iter()
        .map(|&x| (x as f64 - mean).powi(2))
        .sum::<f64>()
        / count)
        .sqrt()
        .max(1e-9);
    let moment = |k: i32| {
        view.data
            .iter()
            .map(|&x| ((x as f64 - mean) / sd).powi(k))
            .sum::<f64>()
            / count
    };
    out.extend([
        sd as f32,
        moment(3) as f32,
        libm::log(moment(4).max(1e-6)) as f32,
    ]);
    debug_assert_eq!(out.len(), GLOBALS);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stripes_put_their_power_in_their_band_and_a_flat_view_is_finite() {
        let n = 64;
        let mut g = Gray::new(n, n);
        for y in 0..n {
            for x in 0..n {
                g.data[y * n + x] =
                    0.5 + 0.4 * (x as f32 * std::f32::consts::TAU * 8.0 / n as f32).sin();
            }
        }
        let v = measure(&g).unwrap();
        assert_eq!(v.len(), GLOBALS);
        // 8 cycles per view is band 5 (7–10): nearly all the power.
        let bands = &v[12..25];
        let best = (0..13).fold(0, |b, i| if bands[i] > bands[b] { i } else { b });
        assert_eq!(best, 5, "{bands:?}");
        assert!(bands[5] > -0.01, "{}", bands[5]);
        let flat = measure(&Gray {
            width: n,
            height: n,
            data: vec![0.5; n * n],
        })
        .unwrap();
        assert!(flat.iter().all(|x| x.is_finite()), "{flat:?}");
        assert!(measure(&Gray::new(48, 48)).is_err());
    }
}
