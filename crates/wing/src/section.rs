//! The wing split into printable sections (seed 002 eq. 1, per semispan).

/// What went wrong splitting the wing.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SectionError {
    /// A length is out of its domain.
    #[error("wing sections: invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The accepted domain.
        reason: &'static str,
    },
}

/// Which part of the wing a section is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The centre section (width w_c), built from its left edge up.
    Centre,
    /// Left wing (y < 0), built root down on the bed, growing towards −y.
    Left,
    /// Right wing (y > 0), built root down on the bed, growing towards +y.
    Right,
}

/// One section, built standing up: spanwise y maps to machine Z.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// Which part of the wing.
    pub side: Side,
    /// Position along its semispan: 0 for the centre, 1 for the section next to it, …
    pub index: usize,
    /// Spanwise y of the face on the bed \[mm\].
    pub y_bed_mm: f64,
    /// Spanwise y of the top face \[mm\].
    pub y_top_mm: f64,
}

impl Section {
    /// Section height (its span) \[mm\].
    pub fn height_mm(&self) -> f64 {
        (self.y_top_mm - self.y_bed_mm).abs()
    }

    /// +1 when y grows with build height, −1 when it shrinks (left wing).
    pub fn direction(&self) -> f64 {
        if self.side == Side::Left {
            -1.0
        } else {
            1.0
        }
    }
}

/// Sections of a wing of span `span_mm` with a centre section `centre_width_mm` wide (0 for
/// none) and build height limit `z_max_mm`, ordered centre, then right/left pairs outward.
///
/// Per semispan (seed 002 notes, Section split): n_semi = ⌈(b/2 − w_c/2)/z_max⌉ sections of
/// b_sect = (b/2 − w_c/2)/n_semi each; the paper's eq. (1), b_sect = (b − w_c)/⌈(b − w_c)/z_max⌉,
/// can give an odd, asymmetric count.
///
/// # Errors
/// Non-finite or non-positive span or z_max, a negative centre width, a centre at least as
/// wide as the span, or a centre taller than z_max.
pub fn split(
    span_mm: f64,
    centre_width_mm: f64,
    z_max_mm: f64,
) -> Result<Vec<Section>, SectionError> {
    let bad = |name, value, reason| {
        Err(SectionError::InvalidParameter {
            name,
            value,
            reason,
        })
    };
    if !(span_mm.is_finite() && span_mm > 0.0) {
        return bad("span_mm", span_mm, "must be finite and > 0");
    }
    if !(z_max_mm.is_finite() && z_max_mm > 0.0) {
        return bad("z_max_mm", z_max_mm, "must be finite and > 0");
    }
    if !(centre_width_mm.is_finite() && (0.0..span_mm).contains(&centre_width_mm)) {
        return bad("centre_width_mm", centre_width_mm, "must be in [0, span)");
    }
    if centre_width_mm > z_max_mm {
        return bad(
            "centre_width_mm",
            centre_width_mm,
            "the centre section must fit under z_max",
        );
    }
    let semi = 0.5 * (span_mm - centre_width_mm);
    let n_semi = (semi / z_max_mm).ceil() as usize;
    let b_sect = semi / n_semi as f64;
    let half_c = 0.5 * centre_width_mm;
    let mut out = Vec::with_capacity(2 * n_semi + 1);
    if centre_width_mm > 0.0 {
        out.push(Section {
            side: Side::Centre,
            index: 0,
            y_bed_mm: -half_c,
            y_top_mm: half_c,
        });
    }
    for k in 0..n_semi {
        let (inner, outer) = (half_c + k as f64 * b_sect, half_c + (k + 1) as f64 * b_sect);
        out.push(Section {
            side: Side::Right,
            index: k + 1,
            y_bed_mm: inner,
            y_top_mm: outer,
        });
        out.push(Section {
            side: Side::Left,
            index: k + 1,
            y_bed_mm: -inner,
            y_top_mm: -outer,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table2_span_splits_into_four_per_side() {
        // Notes [derived]: b = 1090, w_c = 50, z_max = 150 → 4 per side of 130 mm.
        let s = split(1090.0, 50.0, 150.0).unwrap();
        assert_eq!(s.len(), 9);
        assert_eq!(s[0].side, Side::Centre);
        for sec in &s[1..] {
            assert!(
                (sec.height_mm() - 130.0).abs() < 1e-9,
                "130 mm per section (notes)"
            );
        }
        let right: f64 = s
            .iter()
            .filter(|x| x.side == Side::Right)
            .map(Section::height_mm)
            .sum();
        assert!((right - 520.0).abs() < 1e-9);
        assert_eq!(s.last().unwrap().y_top_mm, -545.0);
        assert!(s.iter().all(|x| x.height_mm() <= 150.0));
    }

    #[test]
    fn no_centre_and_bad_inputs() {
        let s = split(300.0, 0.0, 150.0).unwrap();
        assert_eq!(s.len(), 2);
        assert!(split(300.0, 200.0, 150.0).is_err());
        assert!(split(300.0, 0.0, 0.0).is_err());
        assert!(split(f64::NAN, 0.0, 10.0).is_err());
        assert!(split(100.0, 100.0, 150.0).is_err());
    }
}
