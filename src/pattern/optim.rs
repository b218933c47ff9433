//! Fit's optimiser settings, re-exported from the shared [`crate::optim`]
//! (where the GA, random search, Nelder–Mead and Adam live) so the Fit
//! request API names them under `pattern`.
pub use crate::optim::{GaOptions, InitMethod};
