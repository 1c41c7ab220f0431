//! The thesis's toolpath data structure (seed 004 §4.2, eq. 7): one row per point
//! `[X Y Z E C(2) N(2) LW/2 h k]`, the segment chainer of §4.3, and a CSV writer.
//!
//! # Row format
//! - `X Y Z`: the point (mm).
//! - `E`: 1 while depositing, 0 otherwise.
//! - `C`: direction to the next point (eq. 12); `N`: its normal, the direction in which the bead
//!   width is measured (eq. 13). The last point of a path copies the previous point's C and N.
//! - `LW/2`: half the bead width (mm); `h`: bead height (mm).
//! - `k`: path identity number (1-based), used to delete, combine and reorder paths.
//! - A break row "0p" is all zeros except `k`; it ends every path (points not connected).
//!
//! # CSV
//! [`write_csv`] writes a header line
//! `x_mm,y_mm,z_mm,e,c_x,c_y,n_x,n_y,half_width_mm,h_mm,k` and one line per row, numbers with
//! Rust's shortest round-trip formatting.

use std::io::{self, Write};

use crate::toolpath::{LayerToolpath, SegmentKind};

/// One row of seed 004 eq. 7.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThesisRow {
    /// X (mm).
    pub x: f64,
    /// Y (mm).
    pub y: f64,
    /// Z (mm).
    pub z: f64,
    /// E: 1 depositing, 0 not (and 0 in a break row).
    pub e: u8,
    /// C: direction vector (eq. 12).
    pub c: [f64; 2],
    /// N: normal vector (eq. 13).
    pub n: [f64; 2],
    /// LW/2: half bead width (mm).
    pub half_width_mm: f64,
    /// h: bead height (mm).
    pub h_mm: f64,
    /// k: path identity number.
    pub k: usize,
}

impl ThesisRow {
    /// The break row "0p" of path `k`.
    pub fn break_row(k: usize) -> Self {
        Self {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            e: 0,
            c: [0.0; 2],
            n: [0.0; 2],
            half_width_mm: 0.0,
            h_mm: 0.0,
            k,
        }
    }

    /// Whether this is a break row.
    pub fn is_break(&self) -> bool {
        self.e == 0 && self.x == 0.0 && self.y == 0.0 && self.z == 0.0
    }
}

/// How C and N are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VectorConvention {
    /// The thesis's eq. 12–13 as printed: C = [±1, dy/dx] (unnormalised), N = [±1, −1/C₂] or an
    /// axis; the side of N is not consistent (harmless, the bead is symmetric).
    PaperLiteral,
    /// Unit direction and its unit left perpendicular (the default for new code).
    #[default]
    Unit,
}

/// Direction C for a step (dx, dy) (seed 004 eq. 12); `[0, 0]` for a zero step.
pub fn direction_c(dx: f64, dy: f64) -> [f64; 2] {
    match (dx, dy) {
        (dx, dy) if dy == 0.0 && dx > 0.0 => [1.0, 0.0],
        (dx, dy) if dy == 0.0 && dx < 0.0 => [-1.0, 0.0],
        (dx, dy) if dx == 0.0 && dy > 0.0 => [0.0, 1.0],
        (dx, dy) if dx == 0.0 && dy < 0.0 => [0.0, -1.0],
        (dx, dy) if dx < 0.0 => [-1.0, -dy / dx],
        (dx, dy) if dx > 0.0 => [1.0, dy / dx],
        _ => [0.0, 0.0],
    }
}

/// Normal N of direction `c` for a step (dx, dy) (seed 004 eq. 13, same case order as eq. 12).
pub fn normal_n(dx: f64, dy: f64, c: [f64; 2]) -> [f64; 2] {
    match (dx, dy) {
        (dx, dy) if dy == 0.0 && dx > 0.0 => [0.0, 1.0],
        (dx, dy) if dy == 0.0 && dx < 0.0 => [0.0, -1.0],
        (dx, dy) if dx == 0.0 && dy > 0.0 => [1.0, 0.0],
        (dx, dy) if dx == 0.0 && dy < 0.0 => [-1.0, 0.0],
        (dx, _) if dx < 0.0 => [-1.0, -1.0 / c[1]],
        (dx, _) if dx > 0.0 => [1.0, -1.0 / c[1]],
        _ => [0.0, 0.0],
    }
}

fn c_and_n(dx: f64, dy: f64, conv: VectorConvention) -> ([f64; 2], [f64; 2]) {
    match conv {
        VectorConvention::PaperLiteral => {
            let c = direction_c(dx, dy);
            (c, normal_n(dx, dy, c))
        }
        VectorConvention::Unit => {
            let l = dx.hypot(dy);
            if l == 0.0 {
                ([0.0; 2], [0.0; 2])
            } else {
                ([dx / l, dy / l], [-dy / l, dx / l])
            }
        }
    }
}

/// A chained point sequence: `Some(point)` or `None` for a break "0p".
pub type Chain = Vec<Option<[f64; 3]>>;

/// Rows for a chain with constant half width and height (seed 004 eq. 7 and 12–13). Paths are
/// numbered k = 1, 2, … in order; each break row carries the k of the path it ends. A chain
/// that does not end in a break gets one.
pub fn rows_from_chain(
    chain: &[Option<[f64; 3]>],
    half_width_mm: f64,
    h_mm: f64,
    conv: VectorConvention,
) -> Vec<ThesisRow> {
    let mut rows = Vec::with_capacity(chain.len() + 1);
    let mut k = 1;
    let mut prev: ([f64; 2], [f64; 2]) = ([0.0; 2], [0.0; 2]);
    for (i, item) in chain.iter().enumerate() {
        match item {
            None => {
                rows.push(ThesisRow::break_row(k));
                k += 1;
                prev = ([0.0; 2], [0.0; 2]);
            }
            Some(p) => {
                let (c, n) = match chain.get(i + 1) {
                    Some(Some(q)) => c_and_n(q[0] - p[0], q[1] - p[1], conv),
                    // Next is 0p (or the end): copy the previous point's C and N.
                    _ => prev,
                };
                prev = (c, n);
                rows.push(ThesisRow {
                    x: p[0],
                    y: p[1],
                    z: p[2],
                    e: 1,
                    c,
                    n,
                    half_width_mm,
                    h_mm,
                    k,
                });
            }
        }
    }
    if rows.last().is_some_and(|r| !r.is_break()) {
        rows.push(ThesisRow::break_row(k));
    }
    rows
}

/// Rows of a planned layer: one path (k = `first_k`, `first_k + 1`, …) per deposit segment,
/// with its per-point LW/2 and h, each followed by a break row. Travel segments are the breaks.
pub fn rows_from_layer(
    layer: &LayerToolpath,
    first_k: usize,
    conv: VectorConvention,
) -> Vec<ThesisRow> {
    let mut rows = Vec::new();
    for (k, s) in (first_k..).zip(
        layer
            .segments
            .iter()
            .filter(|s| s.kind == SegmentKind::Deposit),
    ) {
        let chain: Chain = s
            .points
            .iter()
            .map(|p| Some([p.x_mm, p.y_mm, p.z_mm]))
            .collect();
        let base = rows_from_chain(&chain, 0.0, 0.0, conv);
        for (mut r, p) in base.into_iter().zip(&s.points) {
            r.half_width_mm = p.bead_width_mm / 2.0;
            r.h_mm = p.bead_height_mm;
            r.k = k;
            rows.push(r);
        }
        rows.push(ThesisRow::break_row(k));
    }
    rows
}

/// Writes rows as CSV (format in the module documentation).
///
/// # Errors
/// The writer's errors.
pub fn write_csv<W: Write>(mut w: W, rows: &[ThesisRow]) -> io::Result<()> {
    writeln!(w, "x_mm,y_mm,z_mm,e,c_x,c_y,n_x,n_y,half_width_mm,h_mm,k")?;
    for r in rows {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{},{}",
            r.x, r.y, r.z, r.e, r.c[0], r.c[1], r.n[0], r.n[1], r.half_width_mm, r.h_mm, r.k
        )?;
    }
    Ok(())
}

/// Chains unordered segments into paths separated by breaks (seed 004 §4.3).
///
/// 1. Consecutive segments whose ends meet (within `tol_mm`) form one fragment.
/// 2. The walk starts at a free end (an endpoint shared with no other fragment) when there is
///    one, else at the first fragment's head. The thesis says "the first point", but its
///    published example (P1…P5) only comes out when starting at the free end P1.
/// 3. Fragments are appended forward or reversed while one touches the current end; when none
///    does, a break is appended and a new start chosen the same way.
/// 4. Consecutive duplicate points are removed; the chain ends with a break.
pub fn chain_segments(segments: &[[[f64; 3]; 2]], tol_mm: f64) -> Chain {
    let same = |a: [f64; 3], b: [f64; 3]| {
        (a[0] - b[0]).abs() <= tol_mm
            && (a[1] - b[1]).abs() <= tol_mm
            && (a[2] - b[2]).abs() <= tol_mm
    };
    // Step 1: fragments from consecutive rows.
    let mut frags: Vec<Vec<[f64; 3]>> = Vec::new();
    for s in segments {
        match frags.last_mut() {
            Some(f) if same(*f.last().expect("non-empty"), s[0]) => f.push(s[1]),
            _ => frags.push(vec![s[0], s[1]]),
        }
    }
    let ends = |f: &Vec<[f64; 3]>| (f[0], *f.last().expect("non-empty"));
    let free_start = |frags: &Vec<Vec<[f64; 3]>>| -> Option<[f64; 3]> {
        let all: Vec<[f64; 3]> = frags.iter().flat_map(|f| [ends(f).0, ends(f).1]).collect();
        all.iter()
            .copied()
            .find(|&p| all.iter().filter(|&&q| same(p, q)).count() == 1)
            .or_else(|| frags.first().map(|f| f[0]))
    };
    let mut out: Chain = Vec::new();
    while let Some(mut cur) = free_start(&frags) {
        while let Some(i) = frags
            .iter()
            .position(|f| same(ends(f).0, cur) || same(ends(f).1, cur))
        {
            let mut f = frags.remove(i);
            if !same(f[0], cur) {
                f.reverse();
            }
            cur = *f.last().expect("non-empty");
            out.extend(f.into_iter().map(Some));
        }
        out.push(None);
    }
    out.dedup_by(|b, a| match (a, b) {
        (Some(p), Some(q)) => same(*p, *q),
        _ => false,
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chainer_p1_to_p5_example() {
        let p = |i: f64| [i, i * i, 0.0];
        let (p1, p2, p3, p4, p5) = (p(1.0), p(2.0), p(3.0), p(4.0), p(5.0));
        let chain = chain_segments(&[[p2, p1], [p3, p4], [p4, p5], [p3, p2]], 1e-9);
        assert_eq!(
            chain,
            vec![Some(p1), Some(p2), Some(p3), Some(p4), Some(p5), None],
            "seed 004 §4.3: [P2 P1; P3 P4; P4 P5; P3 P2] chains to [P1,P2,P3,P4,P5,0p]"
        );
    }

    #[test]
    fn chainer_disconnected_paths_get_breaks() {
        let a = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]];
        let b = [[5.0, 0.0, 0.0], [6.0, 0.0, 0.0]];
        let chain = chain_segments(&[a, b], 1e-9);
        assert_eq!(chain.iter().filter(|x| x.is_none()).count(), 2);
        assert_eq!(chain.len(), 6);
    }

    #[test]
    fn rows_match_fig8_fixture() {
        let chain = vec![
            Some([0.0, 0.0, 3.0]),
            Some([1.0, 1.0, 3.0]),
            Some([2.0, 1.0, 3.0]),
            None,
            Some([3.0, 3.0, 3.0]),
            Some([3.0, 4.0, 3.0]),
            None,
        ];
        let rows = rows_from_chain(&chain, 2.5, 1.6, VectorConvention::PaperLiteral);
        let cn: Vec<([f64; 2], [f64; 2], u8, usize)> =
            rows.iter().map(|r| (r.c, r.n, r.e, r.k)).collect();
        assert_eq!(
            cn,
            vec![
                ([1.0, 1.0], [1.0, -1.0], 1, 1),
                ([1.0, 0.0], [0.0, 1.0], 1, 1),
                ([1.0, 0.0], [0.0, 1.0], 1, 1),
                ([0.0, 0.0], [0.0, 0.0], 0, 1),
                ([0.0, 1.0], [1.0, 0.0], 1, 2),
                ([0.0, 1.0], [1.0, 0.0], 1, 2),
                ([0.0, 0.0], [0.0, 0.0], 0, 2),
            ],
            "seed 004 Fig. 8 rows (C, N, E, k)"
        );
        assert!(rows[3].is_break() && rows[6].is_break());
        assert_eq!(rows[0].half_width_mm, 2.5);
        let mut csv = Vec::new();
        write_csv(&mut csv, &rows).unwrap();
        let text = String::from_utf8(csv).unwrap();
        assert_eq!(text.lines().count(), 8);
        assert_eq!(text.lines().nth(1), Some("0,0,3,1,1,1,1,-1,2.5,1.6,1"));
    }

    #[test]
    fn eq12_eq13_all_cases() {
        assert_eq!(direction_c(-2.0, 0.0), [-1.0, 0.0]);
        assert_eq!(direction_c(0.0, -3.0), [0.0, -1.0]);
        assert_eq!(direction_c(-2.0, 1.0), [-1.0, 0.5]);
        let c = direction_c(2.0, 1.0);
        assert_eq!(c, [1.0, 0.5]);
        assert_eq!(normal_n(2.0, 1.0, c), [1.0, -2.0]);
        assert_eq!(normal_n(-2.0, 1.0, [-1.0, 0.5]), [-1.0, -2.0]);
        // N ⟂ C in every oblique case.
        for (dx, dy) in [(1.0, 3.0), (-1.5, 2.0), (2.0, -0.5)] {
            let c = direction_c(dx, dy);
            let n = normal_n(dx, dy, c);
            assert!((c[0] * n[0] + c[1] * n[1]).abs() < 1e-12);
        }
    }
}
