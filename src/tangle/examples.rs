//! The grammars shipped with Filigree (`assets/tangle/*.tangle`): the
//! paper's Fig. 9 leaf and others, each shown in the browser's grammar
//! picker, run by `filigree bench tangle` and tested in `tests/tangle.rs`.
use serde::Serialize;

/// A shipped grammar.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Example {
    pub name: &'static str,
    /// One line on what it shows.
    pub about: &'static str,
    pub grammar: &'static str,
}

/// Every shipped grammar, the paper's first.
pub const EXAMPLES: &[Example] = &[
    Example {
        name: "leaf",
        about: "The paper's Fig. 9 grammar: outlines, placement, splits and regrouping",
        grammar: include_str!("../../assets/tangle/leaf.tangle"),
    },
    Example {
        name: "checkerboard",
        about: "A grid regrouped into alternate cells, each group its own pattern",
        grammar: include_str!("../../assets/tangle/checkerboard.tangle"),
    },
    Example {
        name: "streamlines",
        about: "Circles around a centre and lines following an outline",
        grammar: include_str!("../../assets/tangle/streamlines.tangle"),
    },
    Example {
        name: "pebbles",
        about: "Packed pebbles and hexagons in wavy bands",
        grammar: include_str!("../../assets/tangle/pebbles.tangle"),
    },
    Example {
        name: "letters",
        about: "A typed word's letter outlines, each decorated on its own",
        grammar: include_str!("../../assets/tangle/letters.tangle"),
    },
    Example {
        name: "village",
        about: "A large aggregate of blocks, lots and yards (about 18,000 shapes)",
        grammar: include_str!("../../assets/tangle/village.tangle"),
    },
];

/// The shipped grammar called `name`.
pub fn example(name: &str) -> Option<&'static Example> {
    EXAMPLES.iter().find(|e| e.name == name)
}
