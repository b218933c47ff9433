//! A Micro scene as data: a tree of nodes read from JSON, each a
//! composable signed distance function with parameters.
//!
//! ```json
//! {"type": "union", "children": [
//!   {"type": "particles", "cell": 0.1, "seed": 3, "size": {"dist": "uniform", "min": 0.1, "max": 0.4}},
//!   {"type": "tpms", "surface": "gyroid", "period": 0.5, "thickness": 0.2}
//! ]}
//! ```
//!
//! [`parse`] checks the text (size, nesting, node count, every parameter)
//! and compiles it into a [`Scene`] whose [`Scene::eval`] is normalised by
//! each node's gradient bound: |f(p) − f(q)| ≤ |p − q| everywhere, so
//! sphere tracing never overshoots. Errors are typed, name the field
//! `scene` and, in the message, the node's path (`children.1.size.max`).
use super::cells::{Lattice, Particles, Pile};
pub(crate) use super::checks::{bad, join, num, vec3, WORLD};
use super::periodic::{Periodic, Tpms};
use crate::core::error::{Error, Result};
use crate::core::limits::{
    MAX_MICRO_CHILDREN, MAX_MICRO_DEPTH, MAX_MICRO_NODES, MAX_MICRO_SCENE_BYTES,
};
use crate::micro::sdf3;
use glam::{DMat3, DVec3};
use serde::{Deserialize, Serialize};

/// One node of a scene (JSON object tagged by `type`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Node {
    /// Sphere at `center`.
    Sphere {
        #[serde(default)]
        center: [f64; 3],
        radius: f64,
    },
    /// Axis-aligned box with half sizes `half`, edges rounded by `round`.
    Box {
        #[serde(default)]
        center: [f64; 3],
        half: [f64; 3],
        #[serde(default)]
        round: f64,
    },
    /// Half space `normal · p ≤ offset`.
    Plane {
        normal: [f64; 3],
        #[serde(default)]
        offset: f64,
    },
    /// Suspended particles on a hashed grid (dual grid, 8 cells).
    Particles(Box<Particles>),
    /// A regular lattice of particles selected by congruences (27 cells):
    /// agglomerates, fibres, laminae, porous lattices.
    Lattice(Box<Lattice>),
    /// Piled grains: a full lattice seen through a deformed, rotated domain.
    Pile(Box<Pile>),
    /// Gyroid, diamond or primitive surface.
    Tpms(Tpms),
    /// General sum of products of sines and cosines (Eq. 11).
    Periodic(Periodic),
    /// Union of children; `smooth` > 0 blends them.
    Union {
        children: Vec<Node>,
        #[serde(default)]
        smooth: f64,
    },
    /// Intersection of children.
    Intersection {
        children: Vec<Node>,
        #[serde(default)]
        smooth: f64,
    },
    /// `base` minus every node of `minus`.
    Difference {
        base: Box<Node>,
        minus: Vec<Node>,
        #[serde(default)]
        smooth: f64,
    },
    /// `child` scaled, then rotated, then by `matrix`, then translated.
    Transform {
        child: Box<Node>,
        #[serde(default)]
        matrix: Option<[[f64; 3]; 3]>,
        #[serde(default)]
        rotate: Option<Rotate>,
        #[serde(default = "one")]
        scale: f64,
        #[serde(default)]
        translate: [f64; 3],
    },
    /// Grow (`amount` > 0) or shrink the child.
    Offset { child: Box<Node>, amount: f64 },
    /// A shell of half thickness `thickness` around the child's surface.
    Shell { child: Box<Node>, thickness: f64 },
    /// The child repeated on a grid of `cell` sizes. The child must fit
    /// in one cell around the origin (else the field jumps at cell faces).
    Repeat { child: Box<Node>, cell: [f64; 3] },
}

fn one() -> f64 {
    1.0
}

/// A rotation by `angle` radians about `axis`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotate {
    pub axis: [f64; 3],
    pub angle: f64,
}

/// A compiled scene node: evaluation is normalised (1-Lipschitz).
#[derive(Debug, Clone)]
pub(crate) enum Op {
    Sphere(DVec3, f64),
    Box(DVec3, DVec3, f64),
    Plane(DVec3, f64),
    Particles(Box<Particles>),
    Lattice(Box<Lattice>),
    Pile(Box<Pile>),
    Tpms(Tpms),
    Periodic(Box<Periodic>),
    Union(Vec<Op>, f64),
    Intersection(Vec<Op>, f64),
    Difference(Box<Op>, Vec<Op>, f64),
    /// Inverse linear map, translation, 1 / norm bound of the inverse.
    Transform(Box<Op>, DMat3, DVec3, f64),
    Offset(Box<Op>, f64),
    Shell(Box<Op>, f64),
    Repeat(Box<Op>, DVec3),
}

/// A checked, compiled scene.
#[derive(Debug, Clone)]
pub struct Scene {
    pub(crate) root: Op,
    /// The node tree it was compiled from.
    pub node: Node,
    /// Node count.
    pub nodes: usize,
}

/// Deepest JSON nesting (objects and arrays) of scene text: a node nests
/// at most two levels per scene level (`children` list + object), plus the
/// parameters' own objects and lists.
const MAX_JSON_DEPTH: usize = 2 * MAX_MICRO_DEPTH + 8;

/// Parse and compile scene JSON text.
pub fn parse(text: &str) -> Result<Scene> {
    // A byte order mark (Windows editors write one) is not part of the JSON.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if text.len() > MAX_MICRO_SCENE_BYTES {
        return Err(Error::limit(format!(
            "the scene is {} bytes; at most {MAX_MICRO_SCENE_BYTES} bytes are allowed",
            text.len()
        ))
        .at("scene"));
    }
    if text.trim().is_empty() {
        return Err(Error::input("the scene is empty; give a JSON object such as {\"type\": \"sphere\", \"radius\": 0.5}").at("scene"));
    }
    check_nesting(text)?;
    let mut de = serde_json::Deserializer::from_str(text);
    let node: Node = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        let (line, column) = (inner.line(), inner.column());
        let msg = inner.to_string();
        let msg = msg.split(" at line ").next().unwrap_or(&msg).to_string();
        if line == 0 {
            // A node's fields are read after its `type` (serde buffers
            // them), so neither place nor path survive: find the node that
            // has the field the message names.
            let at = misplaced_key(&msg)
                .and_then(|key| node_with_key(text, key))
                .unwrap_or_default();
            return bad(&at, msg);
        }
        let message = if path == "." || path.is_empty() {
            msg
        } else {
            format!("`{path}`: {msg}")
        };
        Error::Syntax {
            line,
            column,
            message,
        }
        .at("scene")
    })?;
    de.end().map_err(|e| {
        Error::Syntax {
            line: e.line(),
            column: e.column(),
            message: "trailing text after the scene object".into(),
        }
        .at("scene")
    })?;
    compile(node)
}

/// The field an "unknown field `rad`, expected ..." message names.
fn misplaced_key(msg: &str) -> Option<&str> {
    let rest = msg.strip_prefix("unknown field `")?;
    rest.split('`').next()
}

/// The node path (`children.1.children.0`, as [`bad`] names nodes) of the
/// first object in `text` (depth first, keys in order) that has `key`;
/// `None` when it is the root or none has it. Iterative: the text's depth
/// was checked, but no recursion is needed.
fn node_with_key(text: &str, key: &str) -> Option<String> {
    let root: serde_json::Value = serde_json::from_str(text).ok()?;
    let mut stack: Vec<(&serde_json::Value, String)> = vec![(&root, String::new())];
    while let Some((v, path)) = stack.pop() {
        match v {
            serde_json::Value::Object(map) => {
                if map.contains_key(key) {
                    return (!path.is_empty()).then_some(path);
                }
                for (k, child) in map.iter().rev() {
                    stack.push((child, join(&path, k)));
                }
            }
            serde_json::Value::Array(items) => {
                for (i, child) in items.iter().enumerate().rev() {
                    stack.push((child, join(&path, i)));
                }
            }
            _ => {}
        }
    }
    None
}

/// Refuse text nested deeper than [`MAX_JSON_DEPTH`] before serde sees it.
fn check_nesting(text: &str) -> Result<()> {
    let (mut depth, mut in_str, mut esc) = (0usize, false, false);
    let (mut line, mut col) = (1usize, 0usize);
    for c in text.chars() {
        col += 1;
        if c == '\n' {
            line += 1;
            col = 0;
        }
        if in_str {
            match (esc, c) {
                (true, _) => esc = false,
                (false, '\\') => esc = true,
                (false, '"') => in_str = false,
                _ => {}
            }
            continue;
        }
        match c {
            '"' => in_str = true,
            '{' | '[' => {
                depth += 1;
                if depth > MAX_JSON_DEPTH {
                    return Err(Error::Syntax {
                        line,
                        column: col,
                        message: format!(
                            "the scene nests deeper than {MAX_JSON_DEPTH} levels of objects and lists"
                        ),
                    }
                    .at("scene"));
                }
            }
            '}' | ']' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    Ok(())
}

/// Check and compile a node tree.
pub fn compile(node: Node) -> Result<Scene> {
    let mut count = 0;
    let root = build(&node, "", 1, &mut count)?;
    Ok(Scene {
        root,
        node,
        nodes: count,
    })
}

fn children(
    list: &[Node],
    path: &str,
    name: &str,
    depth: usize,
    count: &mut usize,
    min: usize,
) -> Result<Vec<Op>> {
    if list.len() < min {
        return Err(bad(
            &join(path, name),
            format!("needs at least {min} node(s)"),
        ));
    }
    if list.len() > MAX_MICRO_CHILDREN {
        return Err(Error::limit(format!(
            "scene node `{}` has {} children; at most {MAX_MICRO_CHILDREN} are allowed",
            join(path, name),
            list.len()
        ))
        .at("scene"));
    }
    list.iter()
        .enumerate()
        .map(|(i, c)| build(c, &join(path, format!("{name}.{i}")), depth + 1, count))
        .collect()
}

fn build(node: &Node, path: &str, depth: usize, count: &mut usize) -> Result<Op> {
    *count += 1;
    if *count > MAX_MICRO_NODES {
        return Err(
            Error::limit(format!("the scene has more than {MAX_MICRO_NODES} nodes")).at("scene"),
        );
    }
    if depth > MAX_MICRO_DEPTH {
        return Err(Error::limit(format!(
            "scene node `{path}` is nested {depth} levels deep; at most {MAX_MICRO_DEPTH} are allowed"
        ))
        .at("scene"));
    }
    let smooth = |v: f64| num(path, "smooth", v, 0.0, WORLD);
    Ok(match node {
        Node::Sphere { center, radius } => Op::Sphere(
            vec3(path, "center", *center, -WORLD, WORLD)?,
            num(path, "radius", *radius, 0.0, WORLD)?,
        ),
        Node::Box {
            center,
            half,
            round,
        } => Op::Box(
            vec3(path, "center", *center, -WORLD, WORLD)?,
            vec3(path, "half", *half, 0.0, WORLD)?,
            num(path, "round", *round, 0.0, WORLD)?,
        ),
        Node::Plane { normal, offset } => {
            let n = vec3(path, "normal", *normal, -WORLD, WORLD)?;
            if n.length() < 1e-9 {
                return Err(bad(&join(path, "normal"), "must not be zero"));
            }
            Op::Plane(n.normalize(), num(path, "offset", *offset, -WORLD, WORLD)?)
        }
        Node::Particles(p) => Op::Particles(Box::new(p.checked(path)?)),
        Node::Lattice(l) => Op::Lattice(Box::new(l.checked(path)?)),
        Node::Pile(p) => Op::Pile(Box::new(p.checked(path)?)),
        Node::Tpms(t) => Op::Tpms(t.checked(path)?),
        Node::Periodic(p) => Op::Periodic(Box::new(p.checked(path)?)),
        Node::Union {
            children: c,
            smooth: k,
        } => Op::Union(children(c, path, "children", depth, count, 1)?, smooth(*k)?),
        Node::Intersection {
            children: c,
            smooth: k,
        } => Op::Intersection(children(c, path, "children", depth, count, 1)?, smooth(*k)?),
        Node::Difference {
            base,
            minus,
            smooth: k,
        } => Op::Difference(
            Box::new(build(base, &join(path, "base"), depth + 1, count)?),
            children(minus, path, "minus", depth, count, 0)?,
            smooth(*k)?,
        ),
        Node::Transform {
            child,
            matrix,
            rotate,
            scale,
            translate,
        } => {
            let s = num(path, "scale", *scale, 1e-9, WORLD)?;
            let mut a = DMat3::from_diagonal(DVec3::splat(s));
            if let Some(r) = rotate {
                let axis = vec3(&join(path, "rotate"), "axis", r.axis, -WORLD, WORLD)?;
                if axis.length() < 1e-9 {
                    return Err(bad(&join(path, "rotate.axis"), "must not be zero"));
                }
                let angle = num(&join(path, "rotate"), "angle", r.angle, -1e4, 1e4)?;
                a = sdf3::rotation(axis, angle) * a;
            }
            if let Some(m) = matrix {
                for (i, row) in m.iter().enumerate() {
                    vec3(path, &format!("matrix.{i}"), *row, -WORLD, WORLD)?;
                }
                let m = DMat3::from_cols_array_2d(m).transpose();
                a = m * a;
            }
            let det = a.determinant();
            let inv = a.inverse();
            let bound = sdf3::norm_bound(inv);
            if !det.is_finite() || det.abs() < 1e-12 || !bound.is_finite() || bound > 1e9 {
                return Err(bad(
                    path,
                    "the transform is singular or nearly so (it flattens space); \
                     use a matrix with a non-zero determinant and scale > 0",
                ));
            }
            Op::Transform(
                Box::new(build(child, &join(path, "child"), depth + 1, count)?),
                inv,
                vec3(path, "translate", *translate, -WORLD, WORLD)?,
                1.0 / bound,
            )
        }
        Node::Offset { child, amount } => Op::Offset(
            Box::new(build(child, &join(path, "child"), depth + 1, count)?),
            num(path, "amount", *amount, -WORLD, WORLD)?,
        ),
        Node::Shell { child, thickness } => Op::Shell(
            Box::new(build(child, &join(path, "child"), depth + 1, count)?),
            num(path, "thickness", *thickness, 0.0, WORLD)?,
        ),
        Node::Repeat { child, cell } => Op::Repeat(
            Box::new(build(child, &join(path, "child"), depth + 1, count)?),
            vec3(path, "cell", *cell, 1e-6, WORLD)?,
        ),
    })
}

impl Op {
    /// The normalised distance at `p` (1-Lipschitz).
    pub(crate) fn eval(&self, p: DVec3) -> f64 {
        match self {
            Op::Sphere(c, r) => sdf3::sphere(p - *c, *r),
            Op::Box(c, h, r) => sdf3::cuboid(p - *c, (*h - DVec3::splat(*r)).max(DVec3::ZERO)) - r,
            Op::Plane(n, o) => n.dot(p) - o,
            Op::Particles(c) => c.eval(p),
            Op::Lattice(c) => c.eval(p),
            Op::Pile(c) => c.eval(p),
            Op::Tpms(t) => t.eval(p),
            Op::Periodic(t) => t.eval(p),
            Op::Union(cs, k) => {
                let mut v = cs[0].eval(p);
                for c in &cs[1..] {
                    v = sdf3::smin(v, c.eval(p), *k);
                }
                v
            }
            Op::Intersection(cs, k) => {
                let mut v = cs[0].eval(p);
                for c in &cs[1..] {
                    v = sdf3::smax(v, c.eval(p), *k);
                }
                v
            }
            Op::Difference(b, cs, k) => {
                let mut v = b.eval(p);
                for c in cs {
                    v = sdf3::smax(v, -c.eval(p), *k);
                }
                v
            }
            Op::Transform(c, inv, t, s) => c.eval(*inv * (p - *t)) * s,
            Op::Offset(c, a) => c.eval(p) - a,
            Op::Shell(c, t) => c.eval(p).abs() - t,
            Op::Repeat(c, cell) => {
                let q = p - *cell * (p / *cell).round();
                c.eval(q)
            }
        }
    }
}

impl Op {
    /// What one evaluation of this node and its children costs, in units
    /// of about a tenth of a TPMS evaluation (see [`Scene::eval_cost`]).
    fn cost(&self) -> u64 {
        match self {
            Op::Sphere(..) | Op::Box(..) | Op::Plane(..) => 1,
            Op::Tpms(_) | Op::Periodic(_) => 7,
            Op::Pile(_) => 20,
            Op::Particles(_) => 100,
            Op::Lattice(_) => 300,
            Op::Union(c, _) | Op::Intersection(c, _) => 1 + c.iter().map(Op::cost).sum::<u64>(),
            Op::Difference(a, c, _) => 1 + a.cost() + c.iter().map(Op::cost).sum::<u64>(),
            Op::Transform(c, ..) | Op::Offset(c, _) | Op::Shell(c, _) | Op::Repeat(c, _) => {
                1 + c.cost()
            }
        }
    }
}

impl Scene {
    /// What one evaluation of the scene costs, in units of about a tenth
    /// of a TPMS evaluation: the node types' weights summed over the
    /// tree. Measured natively (16 samples per pixel at 96², 2026-12-05),
    /// the shipped scenes run 70–270 million units a second (a gyroid 70,
    /// particles and lattices 85–170, three cheap particle sets 270), so
    /// a count of units bounds a render's time to within about 4×
    /// (`micro::api::MAX_MICRO_RENDER_WORK`).
    pub fn eval_cost(&self) -> u64 {
        self.root.cost()
    }

    /// [`Scene::eval`] at `[x, y, z]`.
    pub fn eval_array(&self, p: [f64; 3]) -> f64 {
        self.eval(DVec3::from_array(p))
    }

    /// The scene's signed distance at `p`, normalised so that it is
    /// 1-Lipschitz (a lower bound of the true distance outside).
    pub fn eval(&self, p: DVec3) -> f64 {
        let v = self.root.eval(p);
        if v.is_nan() {
            f64::INFINITY
        } else {
            v
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_scene_and_the_node() {
        let e = parse(r#"{"type": "sphere", "radius": -1}"#).unwrap_err();
        assert_eq!(e.field(), Some("scene"));
        assert!(e.to_string().contains("`radius`"), "{e}");
        let e = parse(r#"{"type": "union", "children": [{"type": "sphere", "radius": 1}, {"type": "box", "half": [1, 2, -3]}]}"#).unwrap_err();
        assert!(e.to_string().contains("children.1.half.2"), "{e}");
        // A node's unknown field has no place in the text (serde buffers the
        // node to read its `type` first): it names the node instead of
        // "line 0, column 0".
        let e = parse(r#"{"type": "sphere", "radius": 1, "colour": 3}"#).unwrap_err();
        assert_eq!(e.kind(), "invalid-input");
        assert!(
            e.to_string()
                .starts_with("the scene: unknown field `colour`"),
            "{e}"
        );
        let e = parse("{\"type\": \"spere\"}").unwrap_err();
        assert_eq!(e.position(), Some((1, 16)));
        assert_eq!(parse("").unwrap_err().kind(), "invalid-input");
    }

    #[test]
    fn deep_and_large_scenes_are_refused_before_work() {
        let mut s = String::from(r#"{"type": "sphere", "radius": 1}"#);
        for _ in 0..100 {
            s = format!(r#"{{"type": "offset", "amount": 0, "child": {s}}}"#);
        }
        let e = parse(&s).unwrap_err();
        assert!(matches!(e.kind(), "syntax" | "limit"), "{e}");
        let deep = "[".repeat(100_000);
        assert_eq!(parse(&deep).unwrap_err().kind(), "syntax");
        let mut s = String::from(r#"{"type": "sphere", "radius": 1}"#);
        for _ in 0..(MAX_MICRO_DEPTH + 1) {
            s = format!(r#"{{"type": "offset", "amount": 0, "child": {s}}}"#);
        }
        assert_eq!(parse(&s).unwrap_err().kind(), "limit");
        let many: Vec<String> = (0..300)
            .map(|_| r#"{"type": "sphere", "radius": 1}"#.to_string())
            .collect();
        let s = format!(r#"{{"type": "union", "children": [{}]}}"#, many.join(","));
        assert_eq!(parse(&s).unwrap_err().kind(), "limit");
    }

    #[test]
    fn transforms_keep_distances() {
        let s = parse(r#"{"type": "transform", "scale": 2, "translate": [1, 0, 0], "rotate": {"axis": [0, 0, 1], "angle": 1.0}, "child": {"type": "sphere", "radius": 0.5}}"#).unwrap();
        // A sphere of radius 1 at (1, 0, 0).
        assert!((s.eval(DVec3::new(3.0, 0.0, 0.0)) - 1.0).abs() < 1e-12);
        assert!((s.eval(DVec3::new(1.0, 0.0, 0.0)) + 1.0).abs() < 1e-12);
        let e = parse(r#"{"type": "transform", "matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 0]], "child": {"type": "sphere", "radius": 0.5}}"#).unwrap_err();
        assert!(e.to_string().contains("singular"), "{e}");
    }
}
