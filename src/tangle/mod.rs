//! Tangle: pen-and-ink tangle drawings grown from group grammars (paper:
//! `tangle-group-grammars.txt`, spec T1–T9).
//!
//! A tangle is a set of [`Shape`]s ⟨t, g, s; Θ, d⟩: a tag `t`, a group id
//! `g`, a shape id `s` within the group, the geometry Θ (a polygon with
//! holes, [`crate::tangle::geom::polygon::Polygon`]) and an orientation `d`.
//! Rules of a [`ast::Grammar`] rewrite the non-terminal shapes of the
//! lowest group id, one group per expansion step.
pub mod api;
pub mod ast;
pub mod examples;
pub mod expand;
pub mod export;
pub mod geom;
pub mod grammar;
pub mod letters;
pub mod ops;
pub mod place;
pub mod state;
pub mod streamline;

/// The largest side of a start shape (rectangle, circle, letters, drawn
/// polygon or path), in drawing units: 25 times the default 800-unit page.
/// Operators cost with the shape's size over their spacings, and a
/// million-unit rectangle asked one split for four million pieces.
pub const MAX_START_SIDE: f64 = 20_000.0;

use crate::tangle::geom::polygon::Polygon;
use glam::DVec2;
use std::sync::Arc;

/// How a shape is inked.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Ink {
    /// Fill tone: 0 = paper (unfilled), 1 = black.
    pub fill: f32,
    /// Outline drawn in paper white (an inverted shape).
    pub white_lines: bool,
    /// A decoration mark (stipple dot, dash): filled, no outline.
    pub mark: bool,
}

/// One shape of a tangle.
#[derive(Debug, Clone, PartialEq)]
pub struct Shape {
    /// Index into the tangle's tag table.
    pub tag: u32,
    pub group: u32,
    pub id: u32,
    pub poly: Arc<Polygon>,
    /// Unit orientation vector.
    pub dir: DVec2,
    pub ink: Ink,
}
