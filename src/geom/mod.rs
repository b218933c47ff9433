//! Geometry shared by several tools: the one FFT ([`fft`], Micro's Fourier
//! loss and the Texture models' spectral synthesis). A tool's own geometry
//! lives in its folder (`pattern::geom`, `tangle::geom`, `micro::sdf3`);
//! `tests/layers.rs` keeps shared layers below the tools.
pub mod fft;
