//! Learning for the Texture tool: support vector machines ([`svm`]) and
//! the perceptual texture space ([`isomap`]).
pub mod isomap;
pub mod svm;
