//! The integration tests, one module per file beside this one, built as
//! one test binary: one compile of the code they share and one link, where
//! a binary per file linked the library fourteen times. Run a file's tests
//! with its module path, e.g. `cargo test --test integration tangle::`.

mod support {
    pub mod app_projects;
}

mod cli;
mod fit;
mod fit_designs;
mod fuzz_corpus;
mod layers;
mod micro;
mod micro_fit;
mod modules;
mod pixel;
mod pixel_props;
mod project;
mod tangle;
mod texture;
mod texture_asset;
