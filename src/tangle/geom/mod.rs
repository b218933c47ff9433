//! Tangle's building blocks on glam `DVec2`: polygons with holes and their
//! booleans and slices through `i_overlay` ([`polygon`]), insets through
//! `cavalier_contours` ([`offset`]), outlines from SVG and font glyphs
//! ([`svg`]), mean value coordinates ([`mvc`]) and Perlin noise for the
//! wobbly pen ([`noise`]; the Texture models have their own, tuned to
//! their index), and Tangle's sorts by float keys through one sort instance
//! ([`order`]). Only Tangle uses them, so they live in its folder.
pub mod edge_grid;
pub mod mvc;
pub mod noise;
pub mod offset;
pub mod order;
pub mod polygon;
pub mod svg;
