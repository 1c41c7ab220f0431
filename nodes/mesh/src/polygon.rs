//! Plain-polygon helpers on `[[f64; 2]]` rings (closed implicitly: no repeated last point).

/// Signed area by the shoelace formula, mm²: positive for counter-clockwise rings.
pub fn signed_area_mm2(ring: &[[f64; 2]]) -> f64 {
    let n = ring.len();
    if n < 3 {
        return 0.0;
    }
    // Shifted to the first point to keep the products small (less cancellation far from 0).
    let o = ring[0];
    let mut twice = 0.0;
    for i in 1..n - 1 {
        let (a, b) = (ring[i], ring[i + 1]);
        twice += (a[0] - o[0]) * (b[1] - o[1]) - (b[0] - o[0]) * (a[1] - o[1]);
    }
    0.5 * twice
}

/// Even-odd point-in-polygon test (crossing number). Hand-written: it is a dozen lines on the
/// nesting hot path, where building a `cavalier_contours::Polyline` per test would only copy.
/// Points exactly on the boundary may go either way.
pub fn point_in_polygon(p: [f64; 2], ring: &[[f64; 2]]) -> bool {
    let n = ring.len();
    let mut inside = false;
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (ring[i], ring[j]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

/// Axis-aligned bounds `([xmin, ymin], [xmax, ymax])` of a ring.
pub fn bounds(ring: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in ring {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unit_square_area_and_inside() {
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert_eq!(signed_area_mm2(&sq), 1.0);
        let rev: Vec<_> = sq.iter().rev().copied().collect();
        assert_eq!(signed_area_mm2(&rev), -1.0);
        assert!(point_in_polygon([0.5, 0.5], &sq));
        assert!(!point_in_polygon([1.5, 0.5], &sq));
        assert_eq!(signed_area_mm2(&sq[..2]), 0.0);
    }
}
