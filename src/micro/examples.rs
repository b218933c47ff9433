//! The scenes shipped with Filigree (`assets/micro/*.json`), each shown in
//! the browser's scene picker (`micro-examples`) and parsed in the tests
//! below.
use serde::Serialize;

/// A shipped scene.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Example {
    pub name: &'static str,
    /// One line on what it shows.
    pub about: &'static str,
    pub scene: &'static str,
}

/// Every shipped scene.
pub const EXAMPLES: &[Example] = &[
    Example {
        name: "gyroid",
        about: "A sheet gyroid (triply periodic minimal surface)",
        scene: include_str!("../../assets/micro/gyroid.json"),
    },
    Example {
        name: "spheres",
        about: "Suspended spheres of uniformly distributed sizes on a hashed grid",
        scene: include_str!("../../assets/micro/spheres.json"),
    },
    Example {
        name: "agglomerate",
        about: "An agglomerate whose lattice cells are picked by polynomial congruences",
        scene: include_str!("../../assets/micro/agglomerate.json"),
    },
    Example {
        name: "piled",
        about: "A pile of deformed, tilted grains",
        scene: include_str!("../../assets/micro/piled.json"),
    },
    Example {
        name: "fibres",
        about: "Woven fibres: repeated boxes along three axes",
        scene: include_str!("../../assets/micro/fibres.json"),
    },
    Example {
        name: "multiscale",
        about: "Particles of mixed shapes with a graded density, over a finer structure",
        scene: include_str!("../../assets/micro/multiscale.json"),
    },
    Example {
        name: "ice",
        about: "Ice with air bubbles: large and sparse at the top, small and dense below",
        scene: include_str!("../../assets/micro/ice.json"),
    },
    Example {
        name: "blood",
        about: "A cloud of randomly oriented red blood cells",
        scene: include_str!("../../assets/micro/blood.json"),
    },
    Example {
        name: "fibre-agglomerate",
        about: "Fibres grown from lattice spheres picked along lines by congruences and fused by smooth-min",
        scene: include_str!("../../assets/micro/fibre-agglomerate.json"),
    },
    Example {
        name: "rock-pile",
        about: "A rock pile: the lattice turned by a polynomial angle θ(p), its grains deformed from convex at the bottom to concave at the top",
        scene: include_str!("../../assets/micro/rock-pile.json"),
    },
    Example {
        name: "gyroid-paper",
        about: "Paper fibres: a gyroid stretched along x, cut to a sheet",
        scene: include_str!("../../assets/micro/gyroid-paper.json"),
    },
];

/// The shipped scene called `name`.
pub fn example(name: &str) -> Option<&'static Example> {
    EXAMPLES.iter().find(|e| e.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_scene_parses_and_names_are_unique() {
        for (i, e) in EXAMPLES.iter().enumerate() {
            crate::micro::scene::parse(e.scene).unwrap_or_else(|err| panic!("{}: {err}", e.name));
            assert_eq!(example(e.name).map(|x| x.name), Some(e.name));
            assert!(EXAMPLES[..i].iter().all(|o| o.name != e.name));
        }
    }
}
