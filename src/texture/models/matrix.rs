//! Matrix transformation: a lattice of textons seen through an integer
//! 2×2 matrix M on the torus. Every point p is mapped to q = M·p (mod 1)
//! and shows the texton at q; an integer matrix keeps the result tileable
//! while shearing, stretching and repeating the motif into oblique
//! lattices. A second layer through M² (weighted by `layer2`) adds a finer
//! transformed copy.
use super::common::{normalise, texton, SHAPES};
use super::{int, real, Family, Model, ParamSpec};

const PARAMS: &[ParamSpec] = &[
    int("a", 1.0, 6.0, 3.0),
    int("b", -4.0, 4.0, 1.0),
    int("c", -4.0, 4.0, -1.0),
    int("d", 1.0, 6.0, 3.0),
    real("size", 0.2, 0.5, 0.4),
    int("shape", 0.0, 4.0, 0.0),
    real("layer2", 0.0, 0.6, 0.0),
];

/// M = [[a, b], [c, d]]; `size` is the texton radius in the transformed
/// unit cell; `shape` the texton.
pub const MATRIX: Model = Model {
    id: "matrix-transformation",
    name: "Matrix Transformation",
    family: Family::MatrixTransformation,
    params: PARAMS,
    generate: matrix,
};

fn matrix(p: &[f64], _seed: u64, n: usize) -> Vec<f32> {
    let m = [p[0] as f32, p[1] as f32, p[2] as f32, p[3] as f32];
    let m2 = [
        m[0] * m[0] + m[1] * m[2],
        m[0] * m[1] + m[1] * m[3],
        m[2] * m[0] + m[3] * m[2],
        m[2] * m[1] + m[3] * m[3],
    ];
    let r = p[4] as f32;
    let shape = (p[5] as usize).min(SHAPES - 1);
    let w2 = p[6] as f32;
    let motif = |mm: &[f32; 4], x: f32, y: f32| {
        let qx = mm[0] * x + mm[1] * y;
        let qy = mm[2] * x + mm[3] * y;
        let (u, v) = (qx - qx.floor() - 0.5, qy - qy.floor() - 0.5);
        texton(shape, u / r, v / r)
    };
    let mut h = vec![0.0f32; n * n];
    for y in 0..n {
        // Integer coordinates keep the products exact before the fraction.
        let py = (y as f32 + 0.5) / n as f32;
        for x in 0..n {
            let px = (x as f32 + 0.5) / n as f32;
            let mut v = motif(&m, px, py);
            if w2 > 0.0 {
                v += w2 * motif(&m2, px, py);
            }
            h[y * n + x] = v;
        }
    }
    normalise(&mut h);
    h
}
