pub mod bench;
pub mod fit;
pub mod fit_bench;
pub mod inspect;
pub mod pixel;

use std::path::Path;

/// Read a file, naming it in the error.
pub fn read_file(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// Read and decode an image file with the default limits, naming the file in errors.
#[allow(dead_code)] // used by the tool subcommands
pub fn read_image(path: &Path) -> Result<filigree::raster::Rgba8Image, String> {
    let bytes = read_file(path)?;
    filigree::raster::decode(&bytes, filigree::raster::Limits::default())
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// Median and minimum of a list of timings (seconds).
pub fn min_median(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(|a, b| a.total_cmp(b));
    (v[0], v[v.len() / 2])
}

/// Threads for a parallel run: all cores by default, at most the 64 shards
/// a fit can be split into.
pub fn threads(asked: Option<usize>) -> Result<usize, String> {
    const MAX: usize = 64;
    match asked {
        Some(n @ 1..=MAX) => Ok(n),
        Some(n) => Err(format!("--threads {n}: give 1 to {MAX}")),
        None => Ok(std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
            .min(MAX)),
    }
}
