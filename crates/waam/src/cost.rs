//! Cost model of a WAAM part, before and after the toolpath is known, and of machining from
//! solid (seed 004 eq. 1–6, 15–24, Chart 3). All money in SEK, volumes in m³, times in hours
//! unless a name says otherwise.

use serde::{Deserialize, Serialize};

/// Cost rates and process constants (seed 004 Chart 3; defaults are Chart 3's values).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CostRates {
    /// C_w: wire cost (SEK/kg). Chart 3: 75 (one roll; sensitivity range 35–75).
    pub wire_sek_kg: f64,
    /// C_F: baseplate / stock material cost (SEK/kg). Chart 3: 15.
    pub material_sek_kg: f64,
    /// HR_WAAM: hourly rate of the WAAM cell (SEK/h). Chart 3: 400 (range 150–730).
    pub waam_sek_h: f64,
    /// DR: deposition rate (kg/h). Chart 3: 4 (range 2.94–4).
    pub deposition_kg_h: f64,
    /// HR_M: hourly rate of machining (SEK/h). Chart 3: 400.
    pub machining_sek_h: f64,
    /// MRR: material removal rate (kg/h). Chart 3: 15.
    pub removal_kg_h: f64,
    /// ρ: density (kg/m³). Chart 3: 7850 (steel).
    pub density_kg_m3: f64,
    /// BTF_AM: buy-to-fly ratio of the WAAM part. Chart 3: 1.2 (range 1.1–4).
    pub buy_to_fly: f64,
    /// SS: interlayer cooling time ratio, a multiplier ≥ 1 on arc-on time. Chart 3: 1.1 (1–5).
    pub cooling_ratio: f64,
    /// t_substrate: baseplate manufacturing time (h). Chart 3: 0.25.
    pub substrate_h: f64,
}

impl Default for CostRates {
    fn default() -> Self {
        Self {
            wire_sek_kg: 75.0,
            material_sek_kg: 15.0,
            waam_sek_h: 400.0,
            deposition_kg_h: 4.0,
            machining_sek_h: 400.0,
            removal_kg_h: 15.0,
            density_kg_m3: 7850.0,
            buy_to_fly: 1.2,
            cooling_ratio: 1.1,
            substrate_h: 0.25,
        }
    }
}

/// Part volumes (m³) of seed 004 Chart 3 (defaults are Chart 3's values).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PartVolumes {
    /// V_f: finished product. Chart 3: 0.002546.
    pub finished_m3: f64,
    /// V_s: substrate (baseplate). Chart 3: 0.00162.
    pub substrate_m3: f64,
    /// V_i: initial workpiece when machining from solid. Chart 3: 0.0162.
    pub initial_m3: f64,
    /// V_r: material removed when machining from solid. Chart 3: 0.002546.
    pub removed_m3: f64,
}

impl Default for PartVolumes {
    fn default() -> Self {
        Self {
            finished_m3: 0.002546,
            substrate_m3: 0.00162,
            initial_m3: 0.0162,
            removed_m3: 0.002546,
        }
    }
}

/// Substrate cost C_s = V_s·ρ·C_F + t_substrate·HR_M (seed 004 eq. 2; the text says "sum" but
/// the terms are products). Chart 3 gives 290.755 SEK.
pub fn substrate_cost_sek(rates: &CostRates, volumes: &PartVolumes) -> f64 {
    volumes.substrate_m3 * rates.density_kg_m3 * rates.material_sek_kg
        + rates.substrate_h * rates.machining_sek_h
}

/// Cost estimate before the toolpath exists (seed 004 eq. 1–6), every term named.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PreToolpathCost {
    /// C_s, substrate (eq. 2), SEK.
    pub substrate_sek: f64,
    /// V_d = V_f·BTF_AM − V_s, deposited volume (eq. 3), m³.
    pub deposited_m3: f64,
    /// t_D = V_d·ρ/DR·SS, deposition time including interlayer cooling (eq. 4), h.
    pub deposition_h: f64,
    /// HR_WAAM·t_D, the time part of C_i^AM (eq. 3), SEK.
    pub waam_time_sek: f64,
    /// V_d·ρ·C_w, the wire part of C_i^AM (eq. 3), SEK.
    pub wire_sek: f64,
    /// C_i^AM, deposition cost (eq. 3), SEK.
    pub deposition_sek: f64,
    /// t_m^AM = (V_d + V_s − V_f)·ρ/MRR, machining time (eq. 6), h.
    pub machining_h: f64,
    /// C_m^AM = t_m^AM·HR_M, machining cost (eq. 5), SEK.
    pub machining_sek: f64,
    /// C_AM = C_s + C_i^AM + C_m^AM, total (eq. 1), SEK. Chart 3 gives ≈ 2481.6.
    pub total_sek: f64,
}

/// Pre-toolpath estimate (seed 004 eq. 1–6, modified Martina & Williams model).
pub fn pre_toolpath_cost(rates: &CostRates, volumes: &PartVolumes) -> PreToolpathCost {
    let substrate_sek = substrate_cost_sek(rates, volumes);
    let deposited_m3 = volumes.finished_m3 * rates.buy_to_fly - volumes.substrate_m3;
    let mass_kg = deposited_m3 * rates.density_kg_m3;
    let deposition_h = mass_kg / rates.deposition_kg_h * rates.cooling_ratio;
    let waam_time_sek = rates.waam_sek_h * deposition_h;
    let wire_sek = mass_kg * rates.wire_sek_kg;
    let deposition_sek = waam_time_sek + wire_sek;
    let (machining_h, machining_sek) = machining_after_waam(rates, volumes, deposited_m3);
    PreToolpathCost {
        substrate_sek,
        deposited_m3,
        deposition_h,
        waam_time_sek,
        wire_sek,
        deposition_sek,
        machining_h,
        machining_sek,
        total_sek: substrate_sek + deposition_sek + machining_sek,
    }
}

/// (t_m^AM in h, C_m^AM in SEK) for deposited volume `deposited_m3` (seed 004 eq. 5–6):
/// `t_m^AM = (V_d + V_s − V_f)·ρ / MRR`, `C_m^AM = t_m^AM·HR_M`. The removed volume is what the
/// deposit holds beyond the finished part: positive when the beads enclose the part with a
/// machining allowance, as the slicer plans them (issue 20); a V_d below V_f (beads that miss
/// part of the net shape) would make it negative, which is why the slice job refuses to leave
/// material uncovered.
fn machining_after_waam(rates: &CostRates, volumes: &PartVolumes, deposited_m3: f64) -> (f64, f64) {
    let removed_kg =
        (deposited_m3 + volumes.substrate_m3 - volumes.finished_m3) * rates.density_kg_m3;
    let hours = removed_kg / rates.removal_kg_h;
    (hours, hours * rates.machining_sek_h)
}

/// How the travel (non-depositing) time of a toolpath is known.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum TravelTime {
    /// Given directly in seconds (the thesis's 10 min estimated from 302 starts/stops).
    Seconds(f64),
    /// From the travel distance L_dist (mm) and the travel speed (mm/s), seed 004 eq. 19.
    Distance {
        /// L_dist, total non-depositing distance (mm).
        distance_mm: f64,
        /// Travel speed (mm/s).
        speed_mm_s: f64,
        /// `true`: eq. 19 as printed, `t_trav = L_dist × TS` (dimensionally wrong: mm²/s, taken
        /// numerically as seconds), kept only to reproduce the paper. `false` (the fix):
        /// `t_trav = L_dist / TS`.
        paper_literal: bool,
    },
}

impl TravelTime {
    /// The travel time t_trav in seconds (seed 004 eq. 19, corrected unless `paper_literal`).
    pub fn seconds(&self) -> f64 {
        match *self {
            TravelTime::Seconds(s) => s,
            TravelTime::Distance {
                distance_mm,
                speed_mm_s,
                paper_literal: true,
            } => distance_mm * speed_mm_s,
            TravelTime::Distance {
                distance_mm,
                speed_mm_s,
                paper_literal: false,
            } => distance_mm / speed_mm_s,
        }
    }
}

/// What a toolpath tells the cost model (seed 004 eq. 15–19).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ToolpathTotals {
    /// V_d = Σ V_d,i, deposited volume (eq. 16–17), m³.
    pub deposited_m3: f64,
    /// t_D = Σ L_tp,i / TS_i, arc-on time (eq. 18), s.
    pub deposition_s: f64,
    /// t_wait, programmed waiting (interlayer dwell), s.
    pub wait_s: f64,
    /// t_trav, travel time (eq. 19).
    pub travel: TravelTime,
}

/// Cost after the toolpath is known (seed 004 eq. 20 with eq. 2 and 5–6), every term named.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PostToolpathCost {
    /// C_s, substrate (eq. 2), SEK.
    pub substrate_sek: f64,
    /// t_D, arc-on time (eq. 18), h.
    pub deposition_h: f64,
    /// t_wait, h.
    pub wait_h: f64,
    /// t_trav (eq. 19), h.
    pub travel_h: f64,
    /// HR_WAAM·(t_D + t_wait + t_trav), the time part of eq. 20, SEK.
    pub waam_time_sek: f64,
    /// V_d·ρ·C_w, the wire part of eq. 20, SEK.
    pub wire_sek: f64,
    /// C_i^AM (eq. 20), SEK. The thesis: 1619 SEK for Chart 4.
    pub deposition_sek: f64,
    /// t_m^AM (eq. 6) with the toolpath's V_d, h.
    pub machining_h: f64,
    /// C_m^AM (eq. 5), SEK.
    pub machining_sek: f64,
    /// C_AM = C_s + C_i^AM + C_m^AM (eq. 1), SEK.
    pub total_sek: f64,
}

/// Post-toolpath cost (seed 004 eq. 20: `C_i^AM = HR_WAAM·(t_D + t_wait + t_trav) + V_d·ρ·C_w`).
///
/// Note the thesis's machining figure (403 SEK) is not reproducible from eq. 5–6 (notes B7):
/// with Chart 4's V_d, `V_d + V_s − V_f` is only ≈ 1.5e-5 m³, so `machining_sek` is ≈ 3 SEK.
pub fn post_toolpath_cost(
    rates: &CostRates,
    volumes: &PartVolumes,
    totals: &ToolpathTotals,
) -> PostToolpathCost {
    let substrate_sek = substrate_cost_sek(rates, volumes);
    let deposition_h = totals.deposition_s / 3600.0;
    let wait_h = totals.wait_s / 3600.0;
    let travel_h = totals.travel.seconds() / 3600.0;
    let waam_time_sek = rates.waam_sek_h * (deposition_h + wait_h + travel_h);
    let wire_sek = totals.deposited_m3 * rates.density_kg_m3 * rates.wire_sek_kg;
    let deposition_sek = waam_time_sek + wire_sek;
    let (machining_h, machining_sek) = machining_after_waam(rates, volumes, totals.deposited_m3);
    PostToolpathCost {
        substrate_sek,
        deposition_h,
        wait_h,
        travel_h,
        waam_time_sek,
        wire_sek,
        deposition_sek,
        machining_h,
        machining_sek,
        total_sek: substrate_sek + deposition_sek + machining_sek,
    }
}

/// Cost of machining the part from solid (seed 004 eq. 21–23), every term named.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolidMachiningCost {
    /// C_i^M = V_i·ρ·C_F, initial workpiece (eq. 22), SEK.
    pub workpiece_sek: f64,
    /// C_m^M = V_r·ρ·HR_M/MRR, machining (eq. 23), SEK.
    pub machining_sek: f64,
    /// C_m = C_i^M + C_m^M (eq. 21), SEK.
    pub total_sek: f64,
}

/// Machining from solid (seed 004 eq. 21–23). The thesis's 4815 SEK is not reproducible from
/// Chart 3 (notes B7: eq. 21–23 give 2417–4766 depending on the reading of V_i and V_r).
pub fn solid_machining_cost(rates: &CostRates, volumes: &PartVolumes) -> SolidMachiningCost {
    let workpiece_sek = volumes.initial_m3 * rates.density_kg_m3 * rates.material_sek_kg;
    let machining_sek =
        volumes.removed_m3 * rates.density_kg_m3 * rates.machining_sek_h / rates.removal_kg_h;
    SolidMachiningCost {
        workpiece_sek,
        machining_sek,
        total_sek: workpiece_sek + machining_sek,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn substrate_cost_chart3() {
        let c = substrate_cost_sek(&CostRates::default(), &PartVolumes::default());
        assert!((c - 290.755).abs() < 1e-6, "C_s {c}, thesis 291 (290.755)");
    }

    #[test]
    fn pre_toolpath_chart3() {
        let c = pre_toolpath_cost(&CostRates::default(), &PartVolumes::default());
        assert!(
            (c.deposited_m3 - 0.0014352).abs() < 1e-9,
            "V_d {}",
            c.deposited_m3
        );
        assert!(
            (c.deposition_h - 3.098).abs() < 1e-3,
            "t_D {}, notes 3.098 h",
            c.deposition_h
        );
        assert!(
            (c.deposition_sek - 2084.27).abs() < 0.05,
            "C_i {}",
            c.deposition_sek
        );
        assert!(
            (c.machining_h - 0.2665).abs() < 1e-4,
            "t_m {}",
            c.machining_h
        );
        assert!(
            (c.machining_sek - 106.59).abs() < 0.05,
            "C_m {}",
            c.machining_sek
        );
        assert!(
            (c.total_sek - 2481.6).abs() < 0.1,
            "C_AM {}, notes 2481.6",
            c.total_sek
        );
        let sum = c.substrate_sek + c.waam_time_sek + c.wire_sek + c.machining_sek;
        assert!((sum - c.total_sek).abs() < 1e-9);
    }

    #[test]
    fn post_toolpath_chart4() {
        let r = CostRates::default();
        let v = PartVolumes::default();
        let mut totals = ToolpathTotals {
            deposited_m3: 9.4090e-4,
            deposition_s: 9026.0,
            wait_s: 0.0,
            travel: TravelTime::Seconds(600.0),
        };
        let c = post_toolpath_cost(&r, &v, &totals);
        assert!(
            (c.deposition_sek - 1619.0).abs() < 5.0,
            "C_i^AM {}, thesis 1619 SEK",
            c.deposition_sek
        );
        assert!(
            (c.deposition_sek - 1623.5).abs() < 0.1,
            "notes: 1623.5 with t_D = 9026 s"
        );
        assert!(
            (c.wire_sek - 553.95).abs() < 0.05,
            "wire part {}",
            c.wire_sek
        );
        totals.deposition_s = 2.5 * 3600.0;
        let c = post_toolpath_cost(&r, &v, &totals);
        assert!(
            (c.deposition_sek - 1620.6).abs() < 0.1,
            "notes: 1620.6 with t_D = 2.5 h"
        );
        assert!(
            c.machining_sek < 5.0,
            "eq. 5–6 give ≈3 SEK, not the thesis's 403 (notes B7)"
        );
    }

    #[test]
    fn eq19_corrected_and_paper_literal() {
        let fixed = TravelTime::Distance {
            distance_mm: 12_000.0,
            speed_mm_s: 20.0,
            paper_literal: false,
        };
        let literal = TravelTime::Distance {
            distance_mm: 12_000.0,
            speed_mm_s: 20.0,
            paper_literal: true,
        };
        assert_eq!(fixed.seconds(), 600.0, "L/TS: 12 m at 20 mm/s is 10 min");
        assert_eq!(literal.seconds(), 240_000.0, "eq. 19 as printed: L×TS");
        let r = CostRates::default();
        let v = PartVolumes::default();
        let base = ToolpathTotals {
            deposited_m3: 9.4090e-4,
            deposition_s: 9026.0,
            wait_s: 0.0,
            travel: fixed,
        };
        let a = post_toolpath_cost(&r, &v, &base);
        let b = post_toolpath_cost(
            &r,
            &v,
            &ToolpathTotals {
                travel: literal,
                ..base
            },
        );
        assert!((a.deposition_sek - 1623.5).abs() < 0.1);
        assert!(
            b.deposition_sek > 27_000.0,
            "literal eq. 19 inflates C_i^AM to {}",
            b.deposition_sek
        );
    }

    #[test]
    fn solid_machining_readings() {
        let r = CostRates::default();
        let c = solid_machining_cost(&r, &PartVolumes::default());
        assert!(
            (c.total_sek - 2440.5).abs() < 0.1,
            "Chart 3 V_i, V_r: {}",
            c.total_sek
        );
        let mut v = PartVolumes::default();
        v.removed_m3 = v.initial_m3 - v.finished_m3;
        let c = solid_machining_cost(&r, &v);
        assert!(
            (c.total_sek - 4766.0).abs() < 1.0,
            "V_r = V_i − V_f: {} (notes 4766; thesis 4815, not reproducible)",
            c.total_sek
        );
    }
}
