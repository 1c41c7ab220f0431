//! Airfoil `.dat` files (Selig and Lednicer), then the section operations the planner and the
//! wing designer apply to them.

use cell_airfoil::{Airfoil, SurfaceFunctions};

use crate::{seed_files, text, Target};

const TOKENS: &[&str] = &[
    "1.000000  0.000000\n",
    "0.000000  0.000000\n",
    "  61.  61.\n",
    "\n",
    " 1e308",
    " NaN",
    " -0",
    "\t",
    "#",
];

fn dat(data: &[u8]) {
    let Ok(foil) = Airfoil::from_dat_str(&text(data), "input.dat") else {
        return;
    };
    let _ = foil.chord();
    let _ = foil.signed_area();
    let _ = foil.trailing_edge_gap();
    let n = foil.normalised();
    let _ = n.closed_trailing_edge();
    let _ = n.scaled(200.0);
    let _ = n.resampled_cosine(64);
    if let Ok(s) = SurfaceFunctions::new(&foil) {
        let _ = s.max_thickness();
        let _ = s.x_max_thickness();
        let _ = s.thickness(0.3);
    }
}

fn seeds() -> Vec<Vec<u8>> {
    seed_files("config/airfoils", &[".dat"], 1 << 20)
}

/// The airfoil target.
pub fn targets() -> Vec<Target> {
    vec![Target {
        name: "airfoil_dat",
        about: "UIUC/Selig and Lednicer .dat airfoils, then normalise, resample, surfaces",
        run: dat,
        seeds,
        tokens: TOKENS,
        max_len: 1 << 14,
    }]
}
