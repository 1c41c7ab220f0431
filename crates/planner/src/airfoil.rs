//! Airfoil sections: the [`cell_airfoil`] crate, re-exported so `cell_planner::airfoil::…`
//! paths keep working (UIUC `.dat` input and the 2-D geometry a hot wire follows).

pub use cell_airfoil::*;

/// A shipped foil from `config/airfoils`, scaled to `chord_mm`, for tests across the crate.
#[cfg(test)]
pub(crate) fn test_foil(name: &str, chord_mm: f64) -> Airfoil {
    let path = format!(
        "{}/../../config/airfoils/{name}.dat",
        env!("CARGO_MANIFEST_DIR")
    );
    Airfoil::load(path).unwrap().scaled(chord_mm).unwrap()
}
