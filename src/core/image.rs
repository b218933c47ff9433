//! Pixels as plain data: what crosses the boundary (and a job's progress)
//! undecoded.
use serde::{Deserialize, Serialize};

/// An image as it crosses the boundary undecoded: straight RGBA bytes
/// (a `Uint8Array` in the browser), `width × height × 4` of them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RawImage {
    pub width: u32,
    pub height: u32,
    #[serde(with = "serde_bytes")]
    pub rgba: Vec<u8>,
}
