//! Isomap (Tenenbaum, de Silva & Langford 2000), the paper's way from a
//! similarity matrix to the perceptual texture space: a k-nearest-neighbour
//! graph over the dissimilarities, geodesic distances as shortest paths in
//! it (petgraph's Dijkstra), then classical MDS: the leading eigenvectors
//! of −½ J D² J (nalgebra's `SymmetricEigen::try_new`, which gives up rather
//! than hangs), scaled by the square roots of their eigenvalues.
use crate::core::error::{Error, Result};
use nalgebra::{DMatrix, SymmetricEigen};
use petgraph::graph::{NodeIndex, UnGraph};

/// Geodesic distances over the k-NN graph of the `n × n` dissimilarity
/// matrix `d`. If the graph falls apart, `k` grows until it is connected.
pub fn geodesics(d: &[f64], n: usize, k: usize) -> Result<Vec<f64>> {
    if d.len() != n * n || d.iter().any(|v| !v.is_finite() || *v < 0.0) {
        return Err(Error::input(
            "the dissimilarities must be an n × n matrix of finite values ≥ 0",
        ));
    }
    let mut k = k.clamp(1, n.saturating_sub(1).max(1));
    loop {
        let mut g: UnGraph<(), f64> = UnGraph::with_capacity(n, n * k);
        for _ in 0..n {
            g.add_node(());
        }
        for i in 0..n {
            let mut order: Vec<usize> = (0..n).filter(|&j| j != i).collect();
            order.sort_by(|&a, &b| d[i * n + a].total_cmp(&d[i * n + b]).then(a.cmp(&b)));
            for &j in order.iter().take(k) {
                if g.find_edge(NodeIndex::new(i), NodeIndex::new(j)).is_none() {
                    g.add_edge(NodeIndex::new(i), NodeIndex::new(j), d[i * n + j]);
                }
            }
        }
        let mut out = vec![f64::INFINITY; n * n];
        for i in 0..n {
            for (node, dist) in
                petgraph::algo::dijkstra(&g, NodeIndex::new(i), None, |e| *e.weight())
            {
                out[i * n + node.index()] = dist;
            }
        }
        if out.iter().all(|v| v.is_finite()) || k + 1 >= n {
            // (With k = n − 1 the graph is complete, so every path exists.)
            return Ok(out);
        }
        k = (k * 2).min(n - 1);
    }
}

/// Classical MDS of a distance matrix into `dims` coordinates per point
/// (row-major `n × dims`). Each axis's sign puts its largest-magnitude
/// coordinate positive, so the result is deterministic.
pub fn mds(dist: &[f64], n: usize, dims: usize) -> Result<Vec<f64>> {
    if n == 0 || dims == 0 || dims > n {
        return Err(Error::input(format!(
            "cannot embed {n} points in {dims} dimensions"
        )));
    }
    let sq = |i: usize, j: usize| dist[i * n + j] * dist[i * n + j];
    let row_mean: Vec<f64> = (0..n)
        .map(|i| (0..n).map(|j| sq(i, j)).sum::<f64>() / n as f64)
        .collect();
    let all_mean = row_mean.iter().sum::<f64>() / n as f64;
    let b = DMatrix::from_fn(n, n, |i, j| {
        -0.5 * (sq(i, j) - row_mean[i] - row_mean[j] + all_mean)
    });
    let eig = SymmetricEigen::try_new(b, 1e-12, 100_000)
        .ok_or_else(|| Error::input("the MDS eigen-decomposition did not converge"))?;
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &c| {
        eig.eigenvalues[c]
            .total_cmp(&eig.eigenvalues[a])
            .then(a.cmp(&c))
    });
    let mut out = vec![0.0; n * dims];
    for (axis, &c) in order.iter().take(dims).enumerate() {
        let scale = eig.eigenvalues[c].max(0.0).sqrt();
        let col = eig.eigenvectors.column(c);
        let big = (0..n).fold(0, |best, i| {
            if col[i].abs() > col[best].abs() + 1e-12 {
                i
            } else {
                best
            }
        });
        let sign = if col[big] < 0.0 { -1.0 } else { 1.0 };
        for i in 0..n {
            out[i * dims + axis] = sign * col[i] * scale;
        }
    }
    Ok(out)
}

/// Isomap: `dims` coordinates per point from the dissimilarities `d`.
pub fn isomap(d: &[f64], n: usize, k: usize, dims: usize) -> Result<Vec<f64>> {
    mds(&geodesics(d, n, k)?, n, dims)
}

/// Pearson correlation of two equally long series (0 if either is flat).
pub fn pearson(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len()) as f64;
    if n < 2.0 {
        return 0.0;
    }
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    if saa <= 0.0 || sbb <= 0.0 {
        0.0
    } else {
        sab / (saa * sbb).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;

    fn euclid(points: &[[f64; 3]]) -> Vec<f64> {
        let n = points.len();
        let mut d = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                d[i * n + j] = (0..3)
                    .map(|a| (points[i][a] - points[j][a]).powi(2))
                    .sum::<f64>()
                    .sqrt();
            }
        }
        d
    }

    /// On a Swiss roll, straight-line MDS mixes the turns of the roll;
    /// Isomap unrolls it: its first axis follows the arc length along the
    /// spiral and its second the roll's height.
    #[test]
    fn isomap_unrolls_a_swiss_roll() {
        let mut r = Rng::new(7);
        let n = 500;
        let mut pts = Vec::new();
        let mut arc = Vec::new();
        let mut height = Vec::new();
        for _ in 0..n {
            let t = 1.5 * std::f64::consts::PI * (1.0 + 2.0 * r.f64());
            let h = 15.0 * r.f64();
            pts.push([t * t.cos(), h, t * t.sin()]);
            // Arc length of the spiral r = t from 0: ½(t√(1+t²) + asinh t).
            arc.push(0.5 * (t * (1.0 + t * t).sqrt() + t.asinh()));
            height.push(h);
        }
        let d = euclid(&pts);
        let y = isomap(&d, n, 8, 2).unwrap();
        let axis = |a: usize| (0..n).map(|i| y[i * 2 + a]).collect::<Vec<_>>();
        let c_arc = pearson(&axis(0), &arc).abs();
        let c_h = pearson(&axis(1), &height).abs();
        assert!(c_arc > 0.97, "axis 0 vs arc length: r = {c_arc}");
        assert!(c_h > 0.9, "axis 1 vs height: r = {c_h}");
        // Plain MDS on straight-line distances does not unroll it.
        let flat = mds(&d, n, 2).unwrap();
        let c_flat = pearson(&(0..n).map(|i| flat[i * 2]).collect::<Vec<_>>(), &arc).abs();
        assert!(c_flat < c_arc - 0.1, "MDS alone: r = {c_flat}");
    }

    #[test]
    fn mds_recovers_distances_of_points_in_the_plane() {
        let pts = [
            [0.0, 0.0, 0.0],
            [3.0, 0.0, 0.0],
            [0.0, 4.0, 0.0],
            [3.0, 4.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        let d = euclid(&pts);
        let y = mds(&d, 5, 2).unwrap();
        for i in 0..5 {
            for j in 0..5 {
                let e =
                    ((y[i * 2] - y[j * 2]).powi(2) + (y[i * 2 + 1] - y[j * 2 + 1]).powi(2)).sqrt();
                assert!(
                    (e - d[i * 5 + j]).abs() < 1e-9,
                    "{i}–{j}: {e} vs {}",
                    d[i * 5 + j]
                );
            }
        }
    }

    #[test]
    fn disconnected_neighbourhoods_still_give_finite_geodesics() {
        // Two far clusters: with k = 1 the graph falls apart; k grows.
        let pts = [
            [0.0, 0.0, 0.0],
            [0.1, 0.0, 0.0],
            [100.0, 0.0, 0.0],
            [100.1, 0.0, 0.0],
        ];
        let g = geodesics(&euclid(&pts), 4, 1).unwrap();
        assert!(g.iter().all(|v| v.is_finite()));
        assert!(geodesics(&[0.0, f64::NAN, 1.0, 0.0], 2, 1).is_err());
        assert!(mds(&[0.0], 1, 3).is_err());
    }
}
