//! The generator library (paper §5, Table 1): example programs shipped as
//! text files under `assets/patterns/`, compiled into the crate.

/// One example program.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Generator {
    /// Short kebab-case name, e.g. `circles-grid`.
    pub name: &'static str,
    /// The paper's Table 1 row it stands for, if any.
    pub paper: Option<&'static str>,
    /// Program text.
    pub source: &'static str,
}

/// Every shipped generator: the paper's Table 1 rows, then designer
/// examples (dots, checkers, crosses, waves, scales, graph paper).
pub const GENERATORS: &[Generator] = &[
    Generator {
        name: "circles-grid",
        paper: Some("Circles1"),
        source: include_str!("../../assets/patterns/circles-grid.flg"),
    },
    Generator {
        name: "stripes-dots",
        paper: None,
        source: include_str!("../../assets/patterns/stripes-dots.flg"),
    },
    Generator {
        name: "honeycomb",
        paper: Some("Honeycomb"),
        source: include_str!("../../assets/patterns/honeycomb.flg"),
    },
    Generator {
        name: "spades",
        paper: Some("Spades"),
        source: include_str!("../../assets/patterns/spades.flg"),
    },
    Generator {
        name: "rectangles",
        paper: Some("Rectangles"),
        source: include_str!("../../assets/patterns/rectangles.flg"),
    },
    Generator {
        name: "circles-mix",
        paper: Some("Circles2"),
        source: include_str!("../../assets/patterns/circles-mix.flg"),
    },
    Generator {
        name: "circles-checker",
        paper: Some("Circles3"),
        source: include_str!("../../assets/patterns/circles-checker.flg"),
    },
    Generator {
        name: "stripes",
        paper: Some("Stripes"),
        source: include_str!("../../assets/patterns/stripes.flg"),
    },
    Generator {
        name: "shingles",
        paper: Some("Shingles"),
        source: include_str!("../../assets/patterns/shingles.flg"),
    },
    // Designer examples (issue 9): repeating backgrounds written with `tile`.
    // Stripes and hexagons are `stripes` and `honeycomb` above.
    Generator {
        name: "dots",
        paper: None,
        source: include_str!("../../assets/patterns/dots.flg"),
    },
    Generator {
        name: "checkers",
        paper: None,
        source: include_str!("../../assets/patterns/checkers.flg"),
    },
    Generator {
        name: "crosses",
        paper: None,
        source: include_str!("../../assets/patterns/crosses.flg"),
    },
    Generator {
        name: "waves",
        paper: None,
        source: include_str!("../../assets/patterns/waves.flg"),
    },
    Generator {
        name: "scales",
        paper: None,
        source: include_str!("../../assets/patterns/scales.flg"),
    },
    Generator {
        name: "graph-paper",
        paper: None,
        source: include_str!("../../assets/patterns/graph-paper.flg"),
    },
];

/// The generator called `name`.
pub fn generator(name: &str) -> Option<&'static Generator> {
    GENERATORS.iter().find(|g| g.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::field::Scene;
    use crate::pattern::record::{Program, RecordLimits};

    #[test]
    fn every_generator_records_with_sensible_counts() {
        for g in GENERATORS {
            let p = Program::parse(g.source).unwrap_or_else(|e| panic!("{}: {e}", g.name));
            let rec = p
                .record(&p.defaults(), &RecordLimits::default())
                .unwrap_or_else(|e| panic!("{}: {e}", g.name));
            let n = rec.float_params.len();
            assert!((4..=14).contains(&n), "{}: {n} parameters", g.name);
            eprintln!(
                "{}: {} shapes, {} primitives",
                g.name,
                rec.shapes.len(),
                rec.prims.len()
            );
            // Tiled designs cover the canvas for every value in range, so
            // their counts follow the smallest pitch (graph paper: 338).
            assert!(
                (10..=500).contains(&rec.shapes.len()),
                "{}: {} shapes",
                g.name,
                rec.shapes.len()
            );
            let sc = Scene::new(rec);
            assert!(!sc.channels.is_empty());
        }
    }
}
