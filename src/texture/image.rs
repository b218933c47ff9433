//! The one image type of the Texture tool: a grey image of `f32` values in
//! [0, 1], row-major. Height maps use the same type (heights in [0, 1]) so
//! that models, shading, scales and PCN features share it.

/// A grey image (or height map), row-major, values in [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct Gray {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl Gray {
    /// A black image.
    pub fn new(width: usize, height: usize) -> Gray {
        Gray {
            width,
            height,
            data: vec![0.0; width * height],
        }
    }

    /// The value at (x, y); no bounds beyond the slice's own.
    #[inline]
    pub fn at(&self, x: usize, y: usize) -> f32 {
        self.data[y * self.width + x]
    }

    /// The value at (x, y) with coordinates wrapped (tileable lookups).
    #[inline]
    pub fn wrapped(&self, x: isize, y: isize) -> f32 {
        let w = self.width as isize;
        let h = self.height as isize;
        self.data[(y.rem_euclid(h) * w + x.rem_euclid(w)) as usize]
    }

    /// Stretch the values to [0, 1] (a constant image becomes 0.5).
    pub fn normalise(&mut self) {
        let (lo, hi) = self
            .data
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, h), &v| {
                (l.min(v), h.max(v))
            });
        let span = hi - lo;
        for v in &mut self.data {
            *v = if span > 1e-12 && span.is_finite() {
                (*v - lo) / span
            } else {
                0.5
            };
        }
    }

    /// 8-bit grey bytes (values clamped to [0, 1]).
    pub fn to_bytes(&self) -> Vec<u8> {
        self.data
            .iter()
            .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
            .collect()
    }

    /// From 8-bit grey bytes; `None` if the length is not `width × height`.
    pub fn from_bytes(width: usize, height: usize, bytes: &[u8]) -> Option<Gray> {
        (bytes.len() == width * height).then(|| Gray {
            width,
            height,
            data: bytes.iter().map(|&b| b as f32 / 255.0).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalise_stretches_to_the_unit_range_and_flattens_constants() {
        let mut g = Gray {
            width: 2,
            height: 1,
            data: vec![2.0, 4.0],
        };
        g.normalise();
        assert_eq!(g.data, vec![0.0, 1.0]);
        let mut c = Gray {
            width: 2,
            height: 1,
            data: vec![3.0, 3.0],
        };
        c.normalise();
        assert_eq!(c.data, vec![0.5, 0.5]);
    }

    #[test]
    fn bytes_round_trip_and_wrapped_lookups_tile() {
        let g = Gray::from_bytes(2, 2, &[0, 255, 51, 102]).unwrap();
        assert_eq!(g.to_bytes(), vec![0, 255, 51, 102]);
        assert_eq!(g.wrapped(-1, 0), g.at(1, 0));
        assert_eq!(g.wrapped(2, 3), g.at(0, 1));
        assert!(Gray::from_bytes(2, 2, &[0]).is_none());
    }
}
