//! Grid-based structures (paper §3.1–3.3): suspended particles on a hashed
//! grid with the dual grid of Eq. 4, agglomerates on a regular lattice
//! selected by integer polynomial congruences (Eq. 8–9) in the
//! 27-neighbourhood, and piles (Eq. 10).
//!
//! Distances are computed in cell units (`p_w = p / w`) and every particle
//! lies inside its cell's neighbourhood, so only a few cells are looked at.
//! Beyond those cells there may still be particles closer than the ones
//! found; their distance is at least `C = m + margin − r_max` (`m`: the
//! distance from `p_w` to the boundary of the cells looked at, `margin`:
//! how far every centre stays inside its cell, `r_max`: the largest
//! particle's bounding radius), so the field is `min(d_cells, C)`: exact
//! wherever the true distance is below `C`, never above the true distance
//! and 1-Lipschitz, so sphere tracing cannot overshoot.
use super::checks::{bad, join, num, vec3, WORLD};
use crate::core::error::{Error, Result};
use crate::core::limits::MAX_MICRO_TERMS;
use crate::core::rng::Rng;
use crate::micro::sdf3;
use glam::{DVec3, IVec3};
use serde::{Deserialize, Serialize};

// ------------------------------------------------------------- hashing --

/// The eight prime coefficients `a_ijk` of the multilinear hash (Eq. 1).
const HASH_A: [i64; 8] = [
    1_000_003,
    73_856_093,
    19_349_663,
    83_492_791,
    2_654_435_761,
    805_459_861,
    3_674_653_429,
    2_097_152_011,
];

/// Random numbers drawn per cell (`N` of Eq. 1).
const PER_CELL: i64 = 10;

/// Eq. 1–2: the seed of cell `q`, `t = N Σ a_ijk qx^i qy^j qz^k` (wrapping
/// 64-bit arithmetic), mixed with the node's seed.
pub fn cell_seed(q: IVec3, seed: u64) -> u64 {
    let (x, y, z) = (q.x as i64, q.y as i64, q.z as i64);
    let terms = [
        1,
        x,
        y,
        x.wrapping_mul(y),
        z,
        x.wrapping_mul(z),
        y.wrapping_mul(z),
        x.wrapping_mul(y).wrapping_mul(z),
    ];
    let mut t: i64 = 0;
    for (a, m) in HASH_A.iter().zip(terms) {
        t = t.wrapping_add(a.wrapping_mul(m));
    }
    (t.wrapping_mul(PER_CELL) as u64) ^ seed.wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

/// Cell index of a point in cell units (saturating far away).
fn floor_i(v: DVec3) -> IVec3 {
    let f = v.floor();
    IVec3::new(sat(f.x), sat(f.y), sat(f.z))
}

fn sat(x: f64) -> i32 {
    x.clamp(-1e9, 1e9) as i32
}

// -------------------------------------------------------------- fields --

/// A linear field `value + gradient · p` (world units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Field {
    #[serde(default)]
    pub value: f64,
    #[serde(default)]
    pub gradient: [f64; 3],
}

impl Field {
    pub const fn constant(value: f64) -> Field {
        Field {
            value,
            gradient: [0.0; 3],
        }
    }
    fn at(&self, p: DVec3) -> f64 {
        self.value + DVec3::from_array(self.gradient).dot(p)
    }
    fn check(&self, path: &str, name: &str) -> Result<f64> {
        let p = join(path, name);
        num(&p, "value", self.value, -WORLD, WORLD)?;
        Ok(vec3(&p, "gradient", self.gradient, -WORLD, WORLD)?.length())
    }
}

/// One term `c · x^i y^j z^k` of a real polynomial of the world position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Term {
    pub c: f64,
    #[serde(default)]
    pub x: u32,
    #[serde(default)]
    pub y: u32,
    #[serde(default)]
    pub z: u32,
}

/// Highest degree of a [`Term`].
pub const MAX_POLY_DEGREE: u32 = 6;

/// `v^n` by n − 1 multiplications from the left (the same bits natively and
/// in wasm, unlike `powi`).
fn pow_u(v: f64, n: u32) -> f64 {
    (0..n).fold(1.0, |a, _| a * v)
}

/// A polynomial of the world position: `value + gradient · p + Σ terms`
/// (the pile's rotation angle θ(p) and deformation weight P(p), Eq. 10).
/// Without terms it is the linear [`Field`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Poly {
    #[serde(default)]
    pub value: f64,
    #[serde(default)]
    pub gradient: [f64; 3],
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub terms: Vec<Term>,
}

impl Poly {
    pub const fn constant(value: f64) -> Poly {
        Poly {
            value,
            gradient: [0.0; 3],
            terms: Vec::new(),
        }
    }

    pub(crate) fn at(&self, p: DVec3) -> f64 {
        let mut v = self.value + DVec3::from_array(self.gradient).dot(p);
        for t in &self.terms {
            v += t.c * pow_u(p.x, t.x) * pow_u(p.y, t.y) * pow_u(p.z, t.z);
        }
        v
    }

    /// Checks the numbers; bounds over the cube `|pᵢ| ≤ e`: (largest
    /// |value|, largest |∇|). Without terms: `|value| + |gradient| e√3` and
    /// `|gradient|`, the linear field's.
    fn check(&self, path: &str, name: &str, e: f64) -> Result<(f64, f64)> {
        let p = join(path, name);
        num(&p, "value", self.value, -WORLD, WORLD)?;
        let g = vec3(&p, "gradient", self.gradient, -WORLD, WORLD)?.length();
        if self.terms.len() > MAX_MICRO_TERMS {
            return Err(bad(
                &join(&p, "terms"),
                format!("at most {MAX_MICRO_TERMS} terms"),
            ));
        }
        let (mut vmax, mut dt) = (self.value.abs() + g * e * 3f64.sqrt(), DVec3::ZERO);
        for (i, t) in self.terms.iter().enumerate() {
            let tp = join(&p, format!("terms.{i}"));
            num(&tp, "c", t.c, -WORLD, WORLD)?;
            let deg = t.x as u64 + t.y as u64 + t.z as u64;
            if deg > MAX_POLY_DEGREE as u64 {
                return Err(bad(&tp, format!("degree {deg}: at most {MAX_POLY_DEGREE}")));
            }
            let c = t.c.abs();
            vmax += c * pow_u(e, deg as u32);
            // ∂/∂x of x^i y^j z^k is i x^(i−1) y^j z^k: at most i e^(deg−1).
            let d = |k: u32| {
                if k == 0 {
                    0.0
                } else {
                    c * k as f64 * pow_u(e, deg as u32 - 1)
                }
            };
            dt += DVec3::new(d(t.x), d(t.y), d(t.z));
        }
        Ok((vmax, g + dt.length()))
    }
}

// ------------------------------------------------------------- shapes --

/// A particle shape, scaled so that its bounding sphere has radius 1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    Sphere,
    /// Semi-axes relative to the longest (which becomes 1).
    Ellipsoid {
        axes: [f64; 3],
    },
    /// Tube radius relative to the ring radius.
    Torus {
        ratio: f64,
    },
    /// Half height relative to the radius.
    Cylinder {
        aspect: f64,
    },
    /// Half height relative to the apothem.
    HexPrism {
        aspect: f64,
    },
    /// A red blood cell: a biconcave disc (a torus rim smoothly joined to a
    /// thin disc), after the shape modelled in Kuchel et al. 2021.
    RedBloodCell,
}

impl Shape {
    fn check(&self, path: &str) -> Result<Shape> {
        Ok(match self {
            Shape::Ellipsoid { axes } => {
                let a = vec3(path, "axes", *axes, 1e-3, WORLD)?;
                Shape::Ellipsoid {
                    axes: (a / a.max_element()).to_array(),
                }
            }
            Shape::Torus { ratio } => Shape::Torus {
                ratio: num(path, "ratio", *ratio, 0.01, 1.0)?,
            },
            Shape::Cylinder { aspect } => Shape::Cylinder {
                aspect: num(path, "aspect", *aspect, 0.01, 100.0)?,
            },
            Shape::HexPrism { aspect } => Shape::HexPrism {
                aspect: num(path, "aspect", *aspect, 0.01, 100.0)?,
            },
            s => s.clone(),
        })
    }

    /// Signed distance of the unit-bounded shape at `p` (1-Lipschitz).
    pub fn sdf(&self, p: DVec3) -> f64 {
        match self {
            Shape::Sphere => p.length() - 1.0,
            Shape::Ellipsoid { axes } => sdf3::ellipsoid(p, DVec3::from_array(*axes)),
            Shape::Torus { ratio } => {
                let major = 1.0 / (1.0 + ratio);
                sdf3::torus(p, major, major * ratio)
            }
            Shape::Cylinder { aspect } => {
                let r = 1.0 / (1.0 + aspect * aspect).sqrt();
                sdf3::cylinder(p, r, r * aspect)
            }
            Shape::HexPrism { aspect } => {
                // Corner radius of the hexagon = apothem · 2/√3.
                let c = 2.0 / 3f64.sqrt();
                let r = 1.0 / (c * c + aspect * aspect).sqrt();
                sdf3::hex_prism(p, r, r * aspect)
            }
            Shape::RedBloodCell => {
                let rim = sdf3::torus(p, 0.72, 0.26);
                let disc = sdf3::cylinder(p, 0.72, 0.1);
                sdf3::smin(rim, disc, 0.12)
            }
        }
    }
}

/// One shape of a mixture with its weight.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Choice {
    #[serde(flatten)]
    pub shape: Shape,
    #[serde(default = "one")]
    pub weight: f64,
}

fn one() -> f64 {
    1.0
}

/// Particle radius distribution, in cell widths.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "dist", rename_all = "snake_case", deny_unknown_fields)]
pub enum Size {
    Fixed {
        radius: f64,
    },
    Uniform {
        min: f64,
        max: f64,
    },
    /// Normal, clamped to `[0, max]`.
    Normal {
        mean: f64,
        std: f64,
        max: f64,
    },
}

impl Size {
    fn check(&self, path: &str, limit: f64) -> Result<f64> {
        let p = join(path, "size");
        Ok(match *self {
            Size::Fixed { radius } => num(&p, "radius", radius, 0.0, limit)?,
            Size::Uniform { min, max } => {
                num(&p, "min", min, 0.0, limit)?;
                num(&p, "max", max, min.max(0.0), limit)?
            }
            Size::Normal { mean, std, max } => {
                num(&p, "mean", mean, 0.0, limit)?;
                num(&p, "std", std, 0.0, limit)?;
                num(&p, "max", max, 0.0, limit)?
            }
        })
    }
    fn sample(&self, u1: f64, u2: f64) -> f64 {
        match *self {
            Size::Fixed { radius } => radius,
            Size::Uniform { min, max } => min + (max - min) * u1,
            Size::Normal { mean, std, max } => {
                // Box–Muller with libm.
                let r = (-2.0 * libm::log(1.0 - u1)).sqrt();
                let z = r * libm::cos(std::f64::consts::TAU * u2);
                (mean + std * z).clamp(0.0, max)
            }
        }
    }
}

/// A smooth domain warp `h(p) = amplitude · sin(frequency · p.yzx + phase)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Warp {
    pub amplitude: f64,
    pub frequency: f64,
}

impl Warp {
    fn at(&self, p: DVec3) -> DVec3 {
        let q = p * self.frequency;
        DVec3::new(
            libm::sin(q.y + 1.7),
            libm::sin(q.z + 0.4),
            libm::sin(q.x + 2.9),
        ) * self.amplitude
    }
    /// Bound of the warp's Jacobian norm: each component depends on one
    /// coordinate, with slope at most `amplitude · frequency`.
    fn slope(&self) -> f64 {
        (self.amplitude * self.frequency).abs()
    }
}

// ----------------------------------------------------------- particles --

/// Suspended particles (§3.1): one particle per cell of a grid of width
/// `cell`, found through the dual grid (Eq. 4: the 8 cells around `p`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Particles {
    /// Grid cell width `w`, world units.
    pub cell: f64,
    pub seed: u64,
    /// Shapes mixed by weight (one drawn per particle).
    pub shapes: Vec<Choice>,
    /// Bounding radius in cell widths (at most 1/2: the dual grid).
    pub size: Size,
    /// Radius multiplier at the particle's centre, clamped to [0, 1]
    /// (spatially varying size).
    pub size_scale: Field,
    /// How far centres wander from the cell centre: 0 regular lattice, 1
    /// anywhere in the cell.
    pub jitter: f64,
    /// Acceptance probability g at the cell centre (rejection, Russian roulette).
    pub keep: Field,
    /// Spatially varying offset f(p), world units (added to the distance).
    pub offset: Field,
    /// Domain warp h(p), world units.
    pub warp: Option<Warp>,
    /// Random orientation of each particle (else all aligned).
    pub random_orientation: bool,
    #[serde(skip)]
    pub(crate) c: Derived,
}

/// What checking a grid node derives once.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Derived {
    pub(crate) weights: Vec<f64>,
    pub(crate) r_max: f64,
    pub(crate) margin: f64,
    pub(crate) inv_lip: f64,
}

impl Default for Particles {
    fn default() -> Self {
        Particles {
            cell: 0.1,
            seed: 1,
            shapes: vec![],
            size: Size::Uniform { min: 0.1, max: 0.4 },
            size_scale: Field::constant(1.0),
            jitter: 1.0,
            keep: Field::constant(1.0),
            offset: Field::constant(0.0),
            warp: None,
            random_orientation: true,
            c: Derived::default(),
        }
    }
}

/// The smallest value of `C` at the edge of the cells looked at; below
/// this sphere tracing would crawl along dual-cell faces.
const MIN_CLEARANCE: f64 = 0.02;

fn check_shapes(path: &str, shapes: &[Choice]) -> Result<(Vec<Choice>, Vec<f64>)> {
    if shapes.len() > MAX_MICRO_TERMS {
        return Err(bad(
            &join(path, "shapes"),
            format!("at most {MAX_MICRO_TERMS} shapes"),
        ));
    }
    let mut out = vec![];
    let mut cum = vec![];
    let mut total = 0.0;
    for (i, c) in shapes.iter().enumerate() {
        let p = join(path, format!("shapes.{i}"));
        total += num(&p, "weight", c.weight, 0.0, WORLD)?;
        out.push(Choice {
            shape: c.shape.check(&p)?,
            weight: c.weight,
        });
        cum.push(total);
    }
    if out.is_empty() {
        out.push(Choice {
            shape: Shape::Sphere,
            weight: 1.0,
        });
        cum.push(1.0);
        total = 1.0;
    }
    if total <= 0.0 {
        return Err(bad(&join(path, "shapes"), "the weights add up to 0"));
    }
    Ok((out, cum.iter().map(|c| c / total).collect()))
}

/// One particle: centre (cell units), radius (cell units), shape, rotation.
#[derive(Debug, Clone, Copy)]
pub struct Particle {
    pub centre: DVec3,
    pub radius: f64,
    pub shape: usize,
    /// Three uniform numbers of a random rotation (built only when needed).
    pub rot: Option<[f64; 3]>,
}

impl Particles {
    pub(crate) fn checked(&self, path: &str) -> Result<Particles> {
        let mut t = self.clone();
        num(path, "cell", t.cell, 1e-6, WORLD)?;
        num(path, "jitter", t.jitter, 0.0, 1.0)?;
        let r_max = t.size.check(path, 0.5)?;
        let (shapes, weights) = check_shapes(path, &t.shapes)?;
        t.shapes = shapes;
        t.size_scale.check(path, "size_scale")?;
        t.keep.check(path, "keep")?;
        let off = t.offset.check(path, "offset")?;
        let mut lip = 1.0;
        if let Some(w) = &t.warp {
            let wp = join(path, "warp");
            num(&wp, "amplitude", w.amplitude, 0.0, WORLD)?;
            num(&wp, "frequency", w.frequency, 0.0, WORLD)?;
            lip += w.slope();
        }
        let margin = (1.0 - t.jitter) * 0.5;
        // The nearest dual-cell face is 1/2 away from the 8 cells' edge.
        if 0.5 + margin - r_max < MIN_CLEARANCE {
            return Err(bad(
                &join(path, "size"),
                format!(
                    "particles of radius {r_max} cells with jitter {} may reach past the \
                     dual grid's 8 cells; keep radius < {:.3} (1 − jitter/2 − {MIN_CLEARANCE})",
                    t.jitter,
                    0.5 + margin - MIN_CLEARANCE
                ),
            ));
        }
        t.c = Derived {
            weights,
            r_max,
            margin,
            // d(p) = f(p) + w · d_cells((p + h(p)) / w): slope ≤ |∇f| + 1 + slope(h).
            inv_lip: 1.0 / (lip + off),
        };
        Ok(t)
    }

    /// The particle of cell `q`, if the cell keeps one (Eq. 3 + rejection).
    pub fn particle(&self, q: IVec3) -> Option<Particle> {
        let mut r = Rng::new(cell_seed(q, self.seed));
        let xi: [f64; PER_CELL as usize] = std::array::from_fn(|_| r.f64());
        let centre = q.as_dvec3()
            + DVec3::splat(0.5)
            + (DVec3::new(xi[0], xi[1], xi[2]) - 0.5) * self.jitter;
        let world = centre * self.cell;
        if xi[3] >= self.keep.at(world) {
            return None;
        }
        let scale = self.size_scale.at(world).clamp(0.0, 1.0);
        let radius = (self.size.sample(xi[4], xi[5]) * scale).clamp(0.0, self.c.r_max);
        let shape = self
            .c
            .weights
            .iter()
            .position(|&c| xi[6] < c)
            .unwrap_or(self.c.weights.len() - 1);
        let rot = self.random_orientation.then_some([xi[7], xi[8], xi[9]]);
        Some(Particle {
            centre,
            radius,
            shape,
            rot,
        })
    }

    /// Distance (cell units) from `pw` to particle `pt`.
    pub fn particle_distance(&self, pt: &Particle, pw: DVec3) -> f64 {
        self.particle_distance_below(pt, pw, f64::INFINITY)
    }

    /// [`Self::particle_distance`], or any value ≥ `cut` when the particle's
    /// bounding sphere is already at least `cut` away (so a running minimum
    /// below `cut` is unchanged, exactly).
    pub fn particle_distance_below(&self, pt: &Particle, pw: DVec3, cut: f64) -> f64 {
        if pt.radius <= 0.0 {
            return f64::INFINITY;
        }
        let mut d = pw - pt.centre;
        let bounding = d.length() - pt.radius;
        if bounding >= cut {
            return bounding;
        }
        let shape = &self.shapes[pt.shape].shape;
        if *shape == Shape::Sphere {
            return bounding;
        }
        if let Some([u1, u2, u3]) = pt.rot {
            d = sdf3::random_rotation(u1, u2, u3).transpose() * d;
        }
        // Lower-bound shapes (the ellipsoid) can be far below the true
        // distance away from the particle; the bounding sphere's distance
        // is also a lower bound, and with it no particle is ever closer
        // than its bounding sphere (what the bound `C` relies on).
        (shape.sdf(d / pt.radius) * pt.radius).max(bounding)
    }

    /// The point in cell units (warped), Eq. 6.
    pub fn to_cells(&self, p: DVec3) -> DVec3 {
        let p = match &self.warp {
            Some(w) => p + w.at(p),
            None => p,
        };
        p / self.cell
    }

    /// Eq. 4–6 in cell units: `min(d_8, C)` over the dual grid's 8 cells.
    pub fn cells_distance(&self, pw: DVec3) -> f64 {
        let b = floor_i(pw - DVec3::splat(0.5));
        let mut d = f64::INFINITY;
        for i in 0..8 {
            let q = b + IVec3::new(i & 1, (i >> 1) & 1, (i >> 2) & 1);
            if let Some(pt) = self.particle(q) {
                d = d.min(self.particle_distance_below(&pt, pw, d));
            }
        }
        let lo = pw - b.as_dvec3();
        let m = lo.min(DVec3::splat(2.0) - lo).min_element();
        d.min(self.clearance(m))
    }

    /// `C` for a point `m` cell units inside the cells looked at.
    pub fn clearance(&self, m: f64) -> f64 {
        m + self.c.margin - self.c.r_max
    }

    pub(crate) fn eval(&self, p: DVec3) -> f64 {
        (self.offset.at(p) + self.cell * self.cells_distance(self.to_cells(p))) * self.c.inv_lip
    }
}

// ------------------------------------------------------ congruences (D) --

/// A monomial `c · x^i · y^j · z^k` of an integer polynomial in the cell index.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Monomial {
    pub c: i64,
    #[serde(default)]
    pub x: u32,
    #[serde(default)]
    pub y: u32,
    #[serde(default)]
    pub z: u32,
}

/// Reduce with AND or OR.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Combine {
    /// OR.
    #[default]
    Any,
    /// AND.
    All,
}

/// One residue class of a congruence: `P(q) ≡ residue (mod modulus)`
/// included (`c = 1`) or excluded (`c = −1`, "not congruent").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Class {
    pub residue: i64,
    #[serde(default = "yes")]
    pub include: bool,
}

fn yes() -> bool {
    true
}

/// One polynomial `Pᵢ` with modulus `mᵢ` and its classes, reduced by `combine`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Congruence {
    pub poly: Vec<Monomial>,
    pub modulus: i64,
    pub classes: Vec<Class>,
    #[serde(default)]
    pub combine: Combine,
}

/// Eq. 9: `D(q) = ⊕ᵢ ⊕ⱼ [Pᵢ(q) ≡ cᵢⱼ mᵢⱼ (mod mᵢ)]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Select {
    pub terms: Vec<Congruence>,
    #[serde(default)]
    pub combine: Combine,
}

const MAX_DEGREE: u32 = 8;
const MAX_MODULUS: i64 = 1 << 31;

/// `x^e mod m` with `m` < 2^31 (no overflow in i64 products).
fn pow_mod(x: i64, e: u32, m: i64) -> i64 {
    let x = x.rem_euclid(m);
    let mut r = 1 % m;
    for _ in 0..e {
        r = r * x % m;
    }
    r
}

impl Congruence {
    /// `P(q) mod m` in `0..m`, exactly (modular arithmetic, no overflow).
    pub fn residue(&self, q: IVec3) -> i64 {
        let m = self.modulus;
        let mut s = 0i64;
        for t in &self.poly {
            let v = t.c.rem_euclid(m) * pow_mod(q.x as i64, t.x, m) % m
                * pow_mod(q.y as i64, t.y, m)
                % m
                * pow_mod(q.z as i64, t.z, m)
                % m;
            s = (s + v) % m;
        }
        s
    }

    fn holds(&self, q: IVec3) -> bool {
        let r = self.residue(q);
        let test = |c: &Class| (r == c.residue.rem_euclid(self.modulus)) == c.include;
        match self.combine {
            Combine::Any => self.classes.iter().any(test),
            Combine::All => self.classes.iter().all(test),
        }
    }
}

impl Select {
    fn check(&self, path: &str) -> Result<()> {
        let p = join(path, "select");
        let n: usize = self
            .terms
            .iter()
            .map(|t| t.poly.len() + t.classes.len())
            .sum();
        if self.terms.is_empty() || n > MAX_MICRO_TERMS {
            return Err(bad(
                &join(&p, "terms"),
                format!("needs 1 to {MAX_MICRO_TERMS} monomials and classes in all (got {n})"),
            ));
        }
        for (i, t) in self.terms.iter().enumerate() {
            let tp = join(&p, format!("terms.{i}"));
            if !(1..=MAX_MODULUS).contains(&t.modulus) {
                return Err(bad(
                    &join(&tp, "modulus"),
                    format!("must be in 1..={MAX_MODULUS}"),
                ));
            }
            if t.classes.is_empty() {
                return Err(bad(
                    &join(&tp, "classes"),
                    "needs at least one residue class",
                ));
            }
            for (j, m) in t.poly.iter().enumerate() {
                if m.x.max(m.y).max(m.z) > MAX_DEGREE {
                    return Err(bad(
                        &join(&tp, format!("poly.{j}")),
                        format!("exponents must be at most {MAX_DEGREE}"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// `D(q)`: whether cell `q` keeps its particle.
    pub fn keeps(&self, q: IVec3) -> bool {
        match self.combine {
            Combine::Any => self.terms.iter().any(|t| t.holds(q)),
            Combine::All => self.terms.iter().all(|t| t.holds(q)),
        }
    }
}

// ------------------------------------------------------------- lattice --

/// Agglomeration (§3.2): a regular lattice of spheres of radius up to one
/// cell, kept where `D(q)` holds, merged (smoothly with `smooth` > 0) over
/// the 27 cells around `p`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Lattice {
    pub cell: f64,
    /// Sphere radius, cell widths (≤ 1: the 27-neighbourhood).
    pub radius: f64,
    /// Centre jitter (0: regular lattice).
    pub jitter: f64,
    pub seed: u64,
    /// `D(q)`; none keeps every cell.
    pub select: Option<Select>,
    /// Smooth-min blend width, cell widths.
    pub smooth: f64,
    pub offset: Field,
    #[serde(skip)]
    pub(crate) c: Derived,
}

impl Default for Lattice {
    fn default() -> Self {
        Lattice {
            cell: 0.1,
            radius: 0.6,
            jitter: 0.0,
            seed: 1,
            select: None,
            smooth: 0.0,
            offset: Field::constant(0.0),
            c: Derived::default(),
        }
    }
}

impl Lattice {
    pub(crate) fn checked(&self, path: &str) -> Result<Lattice> {
        let mut t = self.clone();
        num(path, "cell", t.cell, 1e-6, WORLD)?;
        num(path, "radius", t.radius, 0.0, 1.0)?;
        num(path, "jitter", t.jitter, 0.0, 1.0)?;
        num(path, "smooth", t.smooth, 0.0, 1.0)?;
        let off = t.offset.check(path, "offset")?;
        if let Some(s) = &t.select {
            s.check(path)?;
        }
        let margin = (1.0 - t.jitter) * 0.5;
        if 1.0 + margin - t.radius - t.smooth < MIN_CLEARANCE {
            return Err(bad(
                &join(path, "radius"),
                format!(
                    "spheres of radius {} with jitter {} and smooth {} may reach past the 27 cells; \
                     keep radius + smooth < 1 + (1 − jitter)/2",
                    t.radius, t.jitter, t.smooth
                ),
            ));
        }
        t.c = Derived {
            weights: vec![],
            r_max: t.radius,
            margin,
            inv_lip: 1.0 / (1.0 + off),
        };
        Ok(t)
    }

    /// Whether cell `q` holds a particle (`D(q)`).
    pub fn keeps(&self, q: IVec3) -> bool {
        self.select.as_ref().is_none_or(|s| s.keeps(q))
    }

    /// Centre of cell `q`'s sphere, cell units.
    pub fn centre(&self, q: IVec3) -> DVec3 {
        let mut c = q.as_dvec3() + DVec3::splat(0.5);
        if self.jitter > 0.0 {
            let mut r = Rng::new(cell_seed(q, self.seed));
            c += (DVec3::new(r.f64(), r.f64(), r.f64()) - 0.5) * self.jitter;
        }
        c
    }

    /// Eq. 7–8 in cell units: the (smooth) union over the kept cells of the
    /// 27-neighbourhood, capped by `C`.
    pub fn cells_distance(&self, pw: DVec3) -> f64 {
        let q0 = floor_i(pw);
        let mut d = f64::INFINITY;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let q = q0 + IVec3::new(dx, dy, dz);
                    if !self.keeps(q) {
                        continue;
                    }
                    let s = pw.distance(self.centre(q)) - self.radius;
                    d = sdf3::smin(d, s, self.smooth);
                }
            }
        }
        let lo = pw - q0.as_dvec3() + DVec3::ONE;
        let m = lo.min(DVec3::splat(3.0) - lo).min_element();
        d.min(m + self.c.margin - self.radius - self.smooth)
    }

    pub(crate) fn eval(&self, p: DVec3) -> f64 {
        (self.offset.at(p) + self.cell * self.cells_distance(p / self.cell)) * self.c.inv_lip
    }
}

// ---------------------------------------------------------------- pile --

/// Piling (§3.3, Eq. 10): a full lattice of spheres seen through
/// `φ(p) = R_θ(p) p + P(p) N(p)`, with the rotation angle `θ` and the
/// deformation weight `P` polynomials of `p` ([`Poly`]: a linear part plus
/// terms up to degree 6) and `N` a smooth noise vector. `P` moves grains
/// from convex to concave.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Pile {
    pub cell: f64,
    /// Grain radius, cell widths (≤ 1).
    pub radius: f64,
    /// Rotation axis and the angle polynomial θ(p) (radians).
    pub axis: [f64; 3],
    pub angle: Poly,
    /// Deformation weight P(p), world units.
    pub deform: Poly,
    /// Noise N(p): amplitude (relative) and frequency (per world unit).
    pub noise_frequency: f64,
    /// Half size of the region the pile is used in (world units): the
    /// gradient bound of `R_θ(p) p` grows with |p|.
    pub extent: f64,
    #[serde(skip)]
    pub(crate) c: Derived,
    #[serde(skip)]
    pub(crate) axis_n: DVec3,
}

impl Default for Pile {
    fn default() -> Self {
        Pile {
            cell: 0.1,
            radius: 0.5,
            axis: [0.0, 0.0, 1.0],
            angle: Poly::constant(0.0),
            deform: Poly::constant(0.0),
            noise_frequency: 10.0,
            extent: 1.0,
            c: Derived::default(),
            axis_n: DVec3::Z,
        }
    }
}

impl Pile {
    pub(crate) fn checked(&self, path: &str) -> Result<Pile> {
        let mut t = self.clone();
        num(path, "cell", t.cell, 1e-6, WORLD)?;
        num(path, "radius", t.radius, 0.0, 1.0)?;
        num(path, "noise_frequency", t.noise_frequency, 0.0, WORLD)?;
        num(path, "extent", t.extent, 1e-6, WORLD)?;
        let a = vec3(path, "axis", t.axis, -WORLD, WORLD)?;
        if a.length() < 1e-9 {
            return Err(bad(&join(path, "axis"), "must not be zero"));
        }
        t.axis_n = a.normalize();
        let (_, ga) = t.angle.check(path, "angle", t.extent)?;
        let (p_max, gp) = t.deform.check(path, "deform", t.extent)?;
        let r = t.extent * 3f64.sqrt();
        // Over the cube |pᵢ| ≤ extent: ‖Dφ‖ ≤ 1 + |p| |∇θ| + |∇P| |N|max +
        // |P|max |∇N|max, |N|max = √3, |∇N| ≤ frequency.
        let lip = 1.0 + r * ga + gp * 3f64.sqrt() + p_max * t.noise_frequency;
        if !lip.is_finite() || lip > 1e9 {
            return Err(Error::input(format!(
                "scene node `{path}`: the pile's deformation is too steep to trace (gradient bound {lip:.3e})"
            ))
            .at("scene"));
        }
        t.c = Derived {
            weights: vec![],
            r_max: t.radius,
            margin: 0.5,
            inv_lip: 1.0 / lip,
        };
        Ok(t)
    }

    /// `φ(p)`.
    pub fn map(&self, p: DVec3) -> DVec3 {
        let rot = sdf3::rotation(self.axis_n, self.angle.at(p));
        let f = self.noise_frequency;
        let n = DVec3::new(
            libm::sin(f * p.y + 1.3),
            libm::sin(f * p.z + 2.1),
            libm::sin(f * p.x + 0.7),
        );
        rot * p + n * self.deform.at(p)
    }

    pub(crate) fn eval(&self, p: DVec3) -> f64 {
        let pw = self.map(p) / self.cell;
        let q0 = floor_i(pw);
        let mut d = f64::INFINITY;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let c = (q0 + IVec3::new(dx, dy, dz)).as_dvec3() + DVec3::splat(0.5);
                    d = d.min(pw.distance(c) - self.radius);
                }
            }
        }
        let lo = pw - q0.as_dvec3() + DVec3::ONE;
        let m = lo.min(DVec3::splat(3.0) - lo).min_element();
        self.cell * d.min(m + self.c.margin - self.radius) * self.c.inv_lip
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rnd(r: &mut Rng, lo: f64, hi: f64) -> DVec3 {
        DVec3::new(
            r.range_f64(lo, hi),
            r.range_f64(lo, hi),
            r.range_f64(lo, hi),
        )
    }

    /// Eq. 4's 8 cells give exactly the brute-force distance over every
    /// particle of a large region, wherever that is below the bound `C`,
    /// and the same inside/outside everywhere.
    #[test]
    fn dual_grid_equals_brute_force_over_all_particles() {
        let json = r#"{"cell": 1.0, "seed": 11, "jitter": 1.0,
            "size": {"dist": "uniform", "min": 0.05, "max": 0.45},
            "keep": {"value": 0.8, "gradient": [0.02, 0, 0]},
            "shapes": [{"shape": "sphere"}, {"shape": "ellipsoid", "axes": [1, 0.5, 0.3]},
                       {"shape": "torus", "ratio": 0.3}, {"shape": "hex_prism", "aspect": 0.5},
                       {"shape": "cylinder", "aspect": 2}, {"shape": "red_blood_cell"}]}"#;
        let p: Particles = serde_json::from_str(json).unwrap();
        let p = p.checked("").unwrap();
        let mut all = vec![];
        for z in -7..7 {
            for y in -7..7 {
                for x in -7..7 {
                    if let Some(pt) = p.particle(IVec3::new(x, y, z)) {
                        all.push(pt);
                    }
                }
            }
        }
        assert!(all.len() > 1500 && all.len() < 2700, "{}", all.len());
        let mut r = Rng::new(3);
        let (mut exact, mut inside) = (0, 0);
        for _ in 0..4000 {
            let pw = rnd(&mut r, -3.0, 3.0);
            let brute = all
                .iter()
                .map(|pt| p.particle_distance(pt, pw))
                .fold(f64::INFINITY, f64::min);
            let b = (pw - DVec3::splat(0.5)).floor();
            let lo = pw - b;
            let c = p.clearance(lo.min(DVec3::splat(2.0) - lo).min_element());
            let got = p.cells_distance(pw);
            assert_eq!(got, brute.min(c), "at {pw}");
            assert_eq!(got < 0.0, brute < 0.0, "sign at {pw}");
            exact += (brute < c) as usize;
            inside += (brute < 0.0) as usize;
        }
        // The comparison is not vacuous: many points are within C of a
        // particle and some are inside one.
        assert!(exact > 600 && inside > 50, "{exact} {inside}");
    }

    fn brute_poly(poly: &[Monomial], q: IVec3) -> i128 {
        poly.iter()
            .map(|m| {
                m.c as i128
                    * (q.x as i128).pow(m.x)
                    * (q.y as i128).pow(m.y)
                    * (q.z as i128).pow(m.z)
            })
            .sum()
    }

    /// `D(q)` is exactly Eq. 9 computed by brute force in 128-bit integers,
    /// and the lattice has particles in exactly the selected cells.
    #[test]
    fn selection_picks_exactly_the_congruent_cells() {
        let json = r#"{"combine": "any", "terms": [
            {"poly": [{"c": 1, "x": 1}, {"c": -3, "y": 2}, {"c": 5, "x": 1, "z": 3}], "modulus": 7,
             "classes": [{"residue": 2}, {"residue": -1}], "combine": "any"},
            {"poly": [{"c": 2, "y": 1}, {"c": 1, "x": 2, "y": 1}], "modulus": 5,
             "classes": [{"residue": 0, "include": false}, {"residue": 3, "include": false}], "combine": "all"}
        ]}"#;
        let s: Select = serde_json::from_str(json).unwrap();
        s.check("").unwrap();
        let mut kept = 0;
        let mut r = Rng::new(9);
        for _ in 0..3000 {
            let q = IVec3::new(
                r.below(200) as i32 - 100,
                r.below(200) as i32 - 100,
                r.below(200) as i32 - 100,
            );
            let a = brute_poly(&s.terms[0].poly, q).rem_euclid(7);
            let b = brute_poly(&s.terms[1].poly, q).rem_euclid(5);
            let want = (a == 2 || a == 6) || (b != 0 && b != 3);
            assert_eq!(s.keeps(q), want, "q = {q}");
            assert_eq!(s.terms[0].residue(q) as i128, a);
            kept += want as usize;
        }
        assert!(kept > 500 && kept < 2900, "{kept}");
        // Huge indices and exponents do not overflow.
        let big = Congruence {
            poly: vec![Monomial {
                c: i64::MAX,
                x: 8,
                y: 8,
                z: 8,
            }],
            modulus: MAX_MODULUS,
            classes: vec![Class {
                residue: 1,
                include: true,
            }],
            combine: Combine::Any,
        };
        let q = IVec3::new(i32::MAX, i32::MIN, 12345);
        let want = brute_poly(&big.poly[..0], q); // 0: checked separately below
        assert_eq!(want, 0);
        let m = MAX_MODULUS as i128;
        let mut v = (i64::MAX as i128).rem_euclid(m);
        for x in [q.x as i128, q.y as i128, q.z as i128] {
            for _ in 0..8 {
                v = v * x.rem_euclid(m) % m;
            }
        }
        assert_eq!(big.residue(q) as i128, v);

        // In a lattice: a selected cell's centre is inside its sphere; a
        // cell whose whole neighbourhood is unselected is empty.
        let lat: Lattice = serde_json::from_value(serde_json::json!({
            "cell": 1.0, "radius": 0.6, "select": serde_json::from_str::<serde_json::Value>(json).unwrap()
        }))
        .unwrap();
        let lat = lat.checked("").unwrap();
        let (mut ins, mut empty) = (0, 0);
        for z in -6..6 {
            for y in -6..6 {
                for x in -6..6 {
                    let q = IVec3::new(x, y, z);
                    let v = lat.cells_distance(q.as_dvec3() + 0.5);
                    if s.keeps(q) {
                        assert!((v + 0.6).abs() < 1e-12, "{q}: {v}");
                        ins += 1;
                    } else {
                        let none = (-1..=1).all(|a| {
                            (-1..=1).all(|b| (-1..=1).all(|c| !s.keeps(q + IVec3::new(a, b, c))))
                        });
                        if none {
                            assert!(v >= 0.9 - 1e-12, "{q}: {v}");
                            empty += 1;
                        } else {
                            assert!(v > 0.0, "{q}: {v}");
                        }
                    }
                }
            }
        }
        assert!(ins > 100, "{ins} {empty}");
    }

    /// The 27-neighbourhood gives the brute-force union of every kept
    /// sphere wherever it is below `C`.
    #[test]
    fn lattice_equals_brute_force_union() {
        let lat: Lattice = serde_json::from_str(
            r#"{"cell": 1.0, "radius": 0.95, "jitter": 0.6, "seed": 4,
                "select": {"terms": [{"poly": [{"c": 1, "x": 1}, {"c": 2, "y": 1}, {"c": 3, "z": 1}], "modulus": 4, "classes": [{"residue": 1}]}]}}"#,
        )
        .unwrap();
        let lat = lat.checked("").unwrap();
        let mut r = Rng::new(8);
        let mut exact = 0;
        for _ in 0..1500 {
            let pw = rnd(&mut r, -2.0, 2.0);
            let mut brute = f64::INFINITY;
            for z in -6..6 {
                for y in -6..6 {
                    for x in -6..6 {
                        let q = IVec3::new(x, y, z);
                        if lat.keeps(q) {
                            brute = brute.min(pw.distance(lat.centre(q)) - lat.radius);
                        }
                    }
                }
            }
            let q0 = pw.floor();
            let lo = pw - q0 + DVec3::ONE;
            let c = lo.min(DVec3::splat(3.0) - lo).min_element() + 0.2 - 0.95;
            assert_eq!(lat.cells_distance(pw), brute.min(c), "{pw}");
            exact += (brute < c) as usize;
        }
        assert!(exact > 700, "{exact}");
    }

    /// `Poly::at` is the polynomial, and `Poly::check`'s bounds hold over
    /// the cube (value and gradient by central differences, sampled).
    #[test]
    fn polynomial_fields_stay_within_their_bounds() {
        let f: Poly = serde_json::from_value(serde_json::json!({
            "value": 0.3, "gradient": [0.5, -0.2, 0.1],
            "terms": [{"c": 0.8, "x": 1, "y": 1}, {"c": -0.4, "z": 2}, {"c": 0.3, "x": 2, "y": 1, "z": 1}]
        }))
        .unwrap();
        let e = 1.3;
        let (vmax, gmax) = f.check("/", "angle", e).unwrap();
        let mut r = Rng::new(3);
        let (mut v_seen, mut g_seen) = (0.0f64, 0.0f64);
        for _ in 0..20_000 {
            let p = rnd(&mut r, -e, e);
            let want = 0.3 + 0.5 * p.x - 0.2 * p.y + 0.1 * p.z + 0.8 * p.x * p.y - 0.4 * p.z * p.z
                + 0.3 * p.x * p.x * p.y * p.z;
            assert!((f.at(p) - want).abs() < 1e-12, "{} vs {want}", f.at(p));
            let h = 1e-6;
            let g = sdf3::gradient(&mut |q| f.at(q), p, h);
            v_seen = v_seen.max(f.at(p).abs());
            g_seen = g_seen.max(g.length());
        }
        assert!(
            v_seen <= vmax && g_seen <= gmax * (1.0 + 1e-6),
            "{v_seen} ≤ {vmax}, {g_seen} ≤ {gmax}"
        );
        // Not absurdly loose: the corners come within a factor of 3.
        assert!(
            v_seen > vmax / 3.0 && g_seen > gmax / 3.0,
            "{v_seen} / {vmax}, {g_seen} / {gmax}"
        );
        // Without terms: the linear field's bounds.
        let lin = Poly {
            terms: vec![],
            ..f.clone()
        };
        let g = DVec3::new(0.5, -0.2, 0.1).length();
        assert_eq!(
            lin.check("/", "angle", e).unwrap(),
            (0.3 + g * e * 3f64.sqrt(), g)
        );
        // Too high a degree is refused, naming the term.
        let steep = Poly {
            terms: vec![Term {
                c: 1.0,
                x: 4,
                y: 2,
                z: 1,
            }],
            ..lin
        };
        let err = steep.check("/pile", "angle", e).unwrap_err().to_string();
        assert!(err.contains("terms.0") && err.contains("degree 7"), "{err}");
    }

    #[test]
    fn particles_that_could_escape_the_dual_grid_are_refused() {
        let p: Particles =
            serde_json::from_str(r#"{"size": {"dist": "fixed", "radius": 0.5}, "jitter": 1}"#)
                .unwrap();
        let e = p.checked("children.0").unwrap_err();
        assert_eq!(e.field(), Some("scene"));
        assert!(e.to_string().contains("children.0.size"), "{e}");
        let p: Particles =
            serde_json::from_str(r#"{"size": {"dist": "fixed", "radius": 0.5}, "jitter": 0.5}"#)
                .unwrap();
        p.checked("").unwrap();
    }
}
