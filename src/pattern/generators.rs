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

/// Every shipped generator.
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
            assert!(
                (10..=200).contains(&rec.shapes.len()),
                "{}: {} shapes",
                g.name,
                rec.shapes.len()
            );
            let sc = Scene::new(rec);
            assert!(!sc.channels.is_empty());
        }
    }
}
