//! UIUC `.dat` parsing (Selig and Lednicer); see [`super::Airfoil::from_dat_str`].

use nalgebra::Point2;

use super::AirfoilError;

/// Largest |x| or |y| accepted in a `.dat` file, which is chord-normalised.
const COORD_LIMIT: f64 = 2.0;

/// A parsed file, before orientation and de-duplication.
pub(super) struct Parsed {
    /// The name line, if the file has one.
    pub name: Option<String>,
    /// Points in Selig order as read (Lednicer already re-ordered).
    pub points: Vec<Point2<f64>>,
    /// Line of the last coordinate read (or of the last line) for "too few points".
    pub last_line: usize,
}

struct Row {
    line: usize,
    x: f64,
    y: f64,
    /// Blank-line separated block the row belongs to.
    block: usize,
}

pub(super) fn parse(text: &str, file: &str) -> Result<Parsed, AirfoilError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut name = None;
    let mut rows: Vec<Row> = Vec::new();
    let mut block = 0;
    let mut blank_after_data = false;
    let mut seen_first = false;
    let mut last_line = 1;
    // `lines()` also strips the `\r` of CRLF endings.
    for (i, raw) in text.lines().enumerate() {
        let (line, l) = (i + 1, raw.trim());
        last_line = line;
        if l.is_empty() {
            blank_after_data |= !rows.is_empty();
            continue;
        }
        let tokens: Vec<&str> = l.split_whitespace().collect();
        if !seen_first {
            seen_first = true;
            let numeric = tokens.len() == 2 && tokens.iter().all(|t| t.parse::<f64>().is_ok());
            if !numeric {
                name = Some(l.to_string());
                continue;
            }
        }
        if blank_after_data {
            // Prose after the coordinates (e.g. UIUC's notes in ag24.dat) ends the data.
            if tokens[0].parse::<f64>().is_err() {
                break;
            }
            block += 1;
            blank_after_data = false;
        }
        if tokens.len() != 2 {
            return Err(AirfoilError::ColumnCount {
                file: file.into(),
                line,
                found: tokens.len(),
            });
        }
        if rows.len() == super::MAX_POINTS {
            return Err(AirfoilError::TooManyPoints {
                file: file.into(),
                line,
            });
        }
        let x = coordinate(tokens[0], "x", file, line)?;
        let y = coordinate(tokens[1], "y", file, line)?;
        rows.push(Row { line, x, y, block });
    }
    if let Some(r) = rows.last() {
        last_line = r.line;
    }

    let lednicer = rows.first().is_some_and(|r| is_count(r.x) && is_count(r.y));
    let points = if lednicer {
        lednicer_points(&rows, file)?
    } else {
        check_range(&rows, file)?;
        rows.iter().map(|r| Point2::new(r.x, r.y)).collect()
    };
    Ok(Parsed {
        name,
        points,
        last_line,
    })
}

fn coordinate(
    token: &str,
    field: &'static str,
    file: &str,
    line: usize,
) -> Result<f64, AirfoilError> {
    let value: f64 = token.parse().map_err(|_| AirfoilError::NotANumber {
        file: file.into(),
        line,
        field,
        text: token.into(),
    })?;
    if !value.is_finite() {
        return Err(AirfoilError::NonFinite {
            file: file.into(),
            line,
            field,
            value,
        });
    }
    Ok(value)
}

/// A Lednicer point count: a whole number ≥ 2, which no normalised coordinate can be.
fn is_count(v: f64) -> bool {
    v >= COORD_LIMIT && v.fract() == 0.0
}

fn check_range(rows: &[Row], file: &str) -> Result<(), AirfoilError> {
    for r in rows {
        for (field, value) in [("x", r.x), ("y", r.y)] {
            if value.abs() > COORD_LIMIT {
                return Err(AirfoilError::OutOfRange {
                    file: file.into(),
                    line: r.line,
                    field,
                    value,
                    limit: COORD_LIMIT,
                });
            }
        }
    }
    Ok(())
}

/// Lednicer: header row of counts, upper LE → TE, (blank), lower LE → TE. Returns Selig order:
/// upper reversed (TE → LE) then lower (LE → TE); the repeated LE is dropped later.
fn lednicer_points(rows: &[Row], file: &str) -> Result<Vec<Point2<f64>>, AirfoilError> {
    let (header, data) = (&rows[0], &rows[1..]);
    // Counts are whole numbers ≥ 2 here; absurd ones saturate and then fail the count check.
    let (upper, lower) = (header.x as usize, header.y as usize);
    let found_upper = match data.first() {
        // With a blank line between the surfaces, the first block is the upper surface.
        Some(first) if data.iter().any(|r| r.block != first.block) => {
            data.iter().take_while(|r| r.block == first.block).count()
        }
        _ => upper.min(data.len()),
    };
    let found_lower = data.len() - found_upper;
    if (found_upper, found_lower) != (upper, lower) {
        return Err(AirfoilError::LednicerCount {
            file: file.into(),
            line: header.line,
            upper,
            lower,
            found_upper,
            found_lower,
        });
    }
    check_range(data, file)?;
    let pt = |r: &Row| Point2::new(r.x, r.y);
    Ok(data[..upper]
        .iter()
        .rev()
        .map(pt)
        .chain(data[upper..].iter().map(pt))
        .collect())
}

#[cfg(test)]
mod tests {

    /// A named file of `n` coordinate lines.
    fn lines(n: usize) -> String {
        let mut t = String::from("MANY\n");
        for i in 0..n {
            t.push_str(&format!(
                "{} {}\n",
                i as f64 / n as f64,
                (i % 7) as f64 * 1e-3
            ));
        }
        t
    }

    #[test]
    fn coordinate_lines_are_capped() {
        let ok = super::parse(&lines(crate::MAX_POINTS), "ok.dat").unwrap();
        assert_eq!(ok.points.len(), crate::MAX_POINTS);
        let e = super::parse(&lines(crate::MAX_POINTS + 1), "big.dat")
            .err()
            .unwrap();
        assert_eq!(
            e.to_string(),
            "big.dat:20002: more than 20000 coordinate lines: the limit is 20000 points (MAX_POINTS)"
        );
    }

    use super::super::{Airfoil, AirfoilError};

    const SELIG: &str =
        "tiny foil\n1.0 0.0\n0.5 0.06\n0.1 0.04\n0.0 0.0\n0.1 -0.03\n0.5 -0.04\n1.0 0.0\n";

    fn err(text: &str) -> AirfoilError {
        Airfoil::from_dat_str(text, "test.dat").expect_err("should fail")
    }

    #[test]
    fn selig_parses_in_order() {
        let f = Airfoil::from_dat_str(SELIG, "test.dat").unwrap();
        assert_eq!(f.name(), "tiny foil");
        assert_eq!(f.points().len(), 7);
        assert_eq!(f.points()[1].y, 0.06);
        assert_eq!(f.leading_edge_index(), 3);
    }

    #[test]
    fn tolerates_crlf_tabs_blank_lines_and_trailing_spaces() {
        let messy = "\u{feff}  tiny foil  \r\n\r\n1.0\t0.0   \r\n0.5   0.06\r\n\r\n0.1 0.04\r\n \t\r\n0.0 0.0\r\n0.1 -0.03\r\n0.5\t-0.04\r\n1.0 0.0";
        let a = Airfoil::from_dat_str(messy, "messy.dat").unwrap();
        let b = Airfoil::from_dat_str(SELIG, "test.dat").unwrap();
        assert_eq!(a.name(), b.name());
        assert_eq!(a.points(), b.points());
    }

    #[test]
    fn missing_name_line_uses_file_stem() {
        let text = SELIG.split_once('\n').unwrap().1;
        let f = Airfoil::from_dat_str(text, "dir/foo.dat").unwrap();
        assert_eq!(f.name(), "foo");
    }

    #[test]
    fn clockwise_file_is_flipped() {
        let mut lines: Vec<&str> = SELIG.lines().collect();
        lines[1..].reverse();
        let f = Airfoil::from_dat_str(&lines.join("\n"), "cw.dat").unwrap();
        let g = Airfoil::from_dat_str(SELIG, "test.dat").unwrap();
        assert_eq!(f.points(), g.points());
    }

    #[test]
    fn duplicate_consecutive_points_are_dropped() {
        let text = SELIG.replace("0.0 0.0\n", "0.0 0.0\n0.0 0.0\n");
        let f = Airfoil::from_dat_str(&text, "dup.dat").unwrap();
        assert_eq!(f.points().len(), 7);
    }

    #[test]
    fn lednicer_is_detected_and_matches_selig() {
        let text = "tiny foil (Lednicer)\n4.  4.\n\n0.0 0.0\n0.1 0.04\n0.5 0.06\n1.0 0.0\n\n0.0 0.0\n0.1 -0.03\n0.5 -0.04\n1.0 0.0\n";
        let f = Airfoil::from_dat_str(text, "l.dat").unwrap();
        let g = Airfoil::from_dat_str(SELIG, "test.dat").unwrap();
        assert_eq!(f.points(), g.points(), "shared LE dropped, Selig order");
        // Without the blank separator the counts split the data.
        let packed = text.replace("1.0 0.0\n\n0.0", "1.0 0.0\n0.0");
        assert_eq!(
            Airfoil::from_dat_str(&packed, "l.dat").unwrap().points(),
            g.points()
        );
    }

    #[test]
    fn lednicer_rewrite_of_a_real_file_loads_identically() {
        // No shipped file is Lednicer, so write naca0012.dat out in that layout (CRLF too).
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../config/airfoils/naca0012.dat"
        );
        let selig = Airfoil::load(path).unwrap();
        let (upper, lower) = (selig.upper_surface(), selig.lower_surface());
        let mut text = format!("NACA 0012\r\n{}.  {}.\r\n\r\n", upper.len(), lower.len());
        for p in upper.iter().rev() {
            text += &format!(" {}\t{} \r\n", p.x, p.y);
        }
        text += "\r\n";
        for p in lower {
            text += &format!("{} {}\r\n", p.x, p.y);
        }
        let lednicer = Airfoil::from_dat_str(&text, "naca0012-lednicer.dat").unwrap();
        assert_eq!(lednicer.points(), selig.points());
    }

    #[test]
    fn trailing_notes_after_blank_line_are_ignored() {
        let text = format!("{SELIG}\nThese notes are not coordinates.\nNor is this.\n");
        assert_eq!(
            Airfoil::from_dat_str(&text, "t.dat")
                .unwrap()
                .points()
                .len(),
            7
        );
    }

    #[test]
    fn error_non_numeric() {
        let e = err(&SELIG.replace("0.5 0.06", "0.5 O.06"));
        assert!(
            matches!(&e, AirfoilError::NotANumber { line: 3, field: "y", text, .. } if text == "O.06"),
            "{e}"
        );
        assert_eq!(
            e.to_string(),
            "test.dat:3: y coordinate `O.06` is not a number"
        );
        let e = err(&SELIG.replace("0.1 0.04", "abc 0.04"));
        assert!(
            matches!(
                e,
                AirfoilError::NotANumber {
                    line: 4,
                    field: "x",
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn error_column_count() {
        let e = err(&SELIG.replace("0.5 0.06", "0.5 0.06 0.1"));
        assert!(
            matches!(
                e,
                AirfoilError::ColumnCount {
                    line: 3,
                    found: 3,
                    ..
                }
            ),
            "{e}"
        );
        let e = err(&SELIG.replace("0.5 0.06", "0.5"));
        assert!(e.to_string().starts_with("test.dat:3:"), "{e}");
    }

    #[test]
    fn error_too_few_points() {
        let e = err("few\n1 0\n0 0.1\n0 -0.1\n1 0\n");
        assert!(
            matches!(
                e,
                AirfoilError::TooFewPoints {
                    line: 5,
                    found: 4,
                    ..
                }
            ),
            "{e}"
        );
        let e = err("");
        assert!(
            matches!(e, AirfoilError::TooFewPoints { found: 0, .. }),
            "{e}"
        );
    }

    #[test]
    fn error_lednicer_counts() {
        let text = "bad\n5. 4.\n\n0.0 0.0\n0.1 0.04\n0.5 0.06\n1.0 0.0\n\n0.0 0.0\n0.1 -0.03\n0.5 -0.04\n1.0 0.0\n";
        let e = err(text);
        assert!(
            matches!(
                e,
                AirfoilError::LednicerCount {
                    line: 2,
                    upper: 5,
                    lower: 4,
                    found_upper: 4,
                    found_lower: 4,
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn error_out_of_range() {
        let e = err(&SELIG.replace("0.5 -0.04", "50 -0.04"));
        assert!(
            matches!(e, AirfoilError::OutOfRange { line: 7, field: "x", value, .. } if value == 50.0),
            "{e}"
        );
        let e = err(&SELIG.replace("0.5 -0.04", "0.5 -2.5"));
        assert!(
            matches!(e, AirfoilError::OutOfRange { field: "y", .. }),
            "{e}"
        );
    }

    #[test]
    fn error_nan() {
        let e = err(&SELIG.replace("0.1 -0.03", "0.1 NaN"));
        assert!(
            matches!(
                e,
                AirfoilError::NonFinite {
                    line: 6,
                    field: "y",
                    ..
                }
            ),
            "{e}"
        );
        let e = err(&SELIG.replace("0.1 -0.03", "inf -0.03"));
        assert!(
            matches!(e, AirfoilError::NonFinite { field: "x", .. }),
            "{e}"
        );
    }

    #[test]
    fn error_degenerate_and_io() {
        let e = err("flat\n1 0\n0.5 0\n0 0\n0.5 0\n0.8 0\n1 0\n");
        assert!(matches!(e, AirfoilError::Degenerate { .. }), "{e}");
        let e = Airfoil::load("/nonexistent/foil.dat").unwrap_err();
        assert!(
            e.to_string()
                .starts_with("/nonexistent/foil.dat: cannot read"),
            "{e}"
        );
    }

    #[test]
    fn never_panics_on_garbage() {
        for text in [
            "\n\n\n",
            "x",
            "1",
            "2 2\n",
            "3. 3.\n",
            "name\n\n\n1 2 3",
            "a b\nc d\n",
        ] {
            let _ = Airfoil::from_dat_str(text, "g.dat");
        }
    }

    #[test]
    fn every_config_airfoil_loads() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/airfoils");
        let mut count = 0;
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "dat") {
                continue;
            }
            let f = Airfoil::load(&path).unwrap_or_else(|e| panic!("{e}"));
            let n = f.normalised();
            assert!(
                f.points().len() > 30,
                "{}: {} points",
                path.display(),
                f.points().len()
            );
            assert!((n.chord() - 1.0).abs() < 1e-9, "{}", path.display());
            assert!(
                (f.chord() - 1.0).abs() < 0.01,
                "{}: chord {}",
                path.display(),
                f.chord()
            );
            assert!(f.signed_area() > 0.0, "{}: anticlockwise", path.display());
            count += 1;
        }
        assert_eq!(
            count, 9,
            "all nine UIUC files copied from shared/data/airfoils"
        );
    }
}
