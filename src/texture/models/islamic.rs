//! Islamic star patterns by Hankin's "polygons in contact" method on a
//! square grid: from the midpoint of every cell edge two rays leave at the
//! contact angle and stop where they meet the rays of the neighbouring
//! edge; the rays, drawn as raised straps, form eight-pointed stars and
//! crosses.
use super::common::normalise;
use super::{int, real, Family, Model, ParamSpec};

const PARAMS: &[ParamSpec] = &[
    int("cells", 1.0, 8.0, 3.0),
    real("contact_angle", 30.0, 80.0, 67.5),
    real("strap", 0.02, 0.12, 0.05),
    real("fill", 0.0, 1.0, 0.3),
];

/// `cells` pattern repeats per side; `contact_angle` (degrees from the
/// edge) sets the star's sharpness; `strap` is the band half-width in
/// cells; `fill` raises the star interiors.
pub const ISLAMIC: Model = Model {
    id: "islamic",
    name: "Islamic Patterns",
    family: Family::Islamic,
    params: PARAMS,
    generate: islamic,
};

/// The 8 segments of one unit cell (Hankin rays from the edge midpoints).
fn segments(theta: f32) -> Vec<[(f32, f32); 2]> {
    let (c, s) = (libm::cosf(theta), libm::sinf(theta));
    // Rays from the bottom midpoint toward the corner (1, 0) meet the
    // mirrored ray of the right midpoint on the line x + y = 1.
    let t = 0.5 / (c + s);
    let mut segs = Vec::with_capacity(8);
    // Bottom edge (0.5, 0): toward +x and −x; the rest by symmetry of the square.
    let base = [
        ((0.5, 0.0), (0.5 + t * c, t * s)),
        ((0.5, 0.0), (0.5 - t * c, t * s)),
    ];
    for &(a, b) in &base {
        for rot in 0..4 {
            let r = |(x, y): (f32, f32)| {
                let (mut x, mut y) = (x - 0.5, y - 0.5);
                for _ in 0..rot {
                    (x, y) = (-y, x);
                }
                (x + 0.5, y + 0.5)
            };
            segs.push([r(a), r(b)]);
        }
    }
    segs
}

fn seg_dist(px: f32, py: f32, a: (f32, f32), b: (f32, f32)) -> f32 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((px - a.0) * dx + (py - a.1) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (ex, ey) = (a.0 + t * dx - px, a.1 + t * dy - py);
    (ex * ex + ey * ey).sqrt()
}

fn islamic(p: &[f64], _seed: u64, n: usize) -> Vec<f32> {
    let cells = p[0] as f32;
    let segs = segments((p[1] as f32).to_radians());
    let w = p[2] as f32;
    let fill = p[3] as f32;
    let mut h = vec![0.0f32; n * n];
    for y in 0..n {
        let fy = (y as f32 + 0.5) / n as f32 * cells;
        let ly = fy - fy.floor();
        for x in 0..n {
            let fx = (x as f32 + 0.5) / n as f32 * cells;
            let lx = fx - fx.floor();
            let mut d = f32::MAX;
            // This cell and its four edge neighbours (straps cross edges).
            for (ox, oy) in [(0.0, 0.0), (1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)] {
                for sg in &segs {
                    d = d.min(seg_dist(lx - ox, ly - oy, sg[0], sg[1]));
                }
            }
            let strap = (1.0 - d / w).max(0.0);
            let strap = strap.sqrt();
            // Star interiors: near the cell centre, inside the rays.
            let r = ((lx - 0.5) * (lx - 0.5) + (ly - 0.5) * (ly - 0.5)).sqrt();
            let inner = fill * 0.4 * (1.0 - (r / 0.35).min(1.0));
            h[y * n + x] = strap.max(inner);
        }
    }
    normalise(&mut h);
    h
}
