//! The arc-welding data a RAPID program declares itself (`rapid.weld: {mode: arc, data:
//! program}`): one `seamdata` and one `welddata` per distinct bead.
//!
//! In arc mode the TCP speed while welding is the welddata's `weld_speed`, not the speeddata
//! of the move (RobotWare Arc, `ArcL`, argument `Speed`), and the travel speed sets the bead
//! width (seed 004 eq. 14, inverted for wall-driven beads). So a bead is the pair (travel
//! speed, wire feed speed) as written, and every distinct pair gets its own welddata: a
//! width change in the plan is a welddata change on the robot.
//!
//! Layouts, RobotWare 6 Arc (the controller's data descriptors `welddata.xml`, `arcdata`,
//! `seamdata.xml` of the Arc option; *Application manual - Arc and Arc Sensor*, RobotWare 6,
//! "Data types"):
//!
//! ```text
//! welddata := [weld_speed, org_weld_speed, main_arc, org_arc]             mm/s, arcdata
//! arcdata  := [sched, mode, voltage, wirefeed, control, current,
//!              voltage2, wirefeed2, control2]                            -, -, V, m/min, -, A
//! seamdata := [purge_time, preflow_time, ign_arc, ign_move_delay, scrape_start,
//!              heat_speed, heat_time, heat_distance, heat_arc, cool_time, fill_time,
//!              fill_arc, bback_time, rback_time, bback_arc, postflow_time]        s, arcdata
//! ```
//!
//! ABB's default literals are `welddata [10,10,[0,…],[0,…]]` and `seamdata
//! [0.2,0.05,[0,…],0,0,0,0,0,[0,…],0,0,[0,…],0.1,0,[0,…],0.05]`. Which components a power
//! source reads depends on its configuration; 0 means not used. The `org_*` components hold
//! the values the FlexPendant's tuning resets to, so they equal the written ones. The Seam
//! and Weld arguments of the Arc instructions are persistent (`PERS`); the data are `LOCAL
//! PERS` in each module that welds, so they can neither take nor give a value to a
//! controller-side persistent of the same name.

use cell_profiles::rapid::{ArcValue, SeamValue};

/// One bead as the program welds it: travel speed (mm/s) and wire feed speed (m/min), both as
/// written in the program (rounded), so equal text means equal welddata.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(super) struct Bead {
    /// `weld_speed`, mm/s.
    pub speed: String,
    /// `main_arc.wirefeed`, m/min.
    pub wire_feed: String,
}

/// Decimal places of the wire feed, m/min (1 mm/min).
pub(super) const WIRE_FEED_DECIMALS: usize = 3;

/// The `arcdata` aggregate of a bead: the profile's power source settings with the bead's
/// wire feed; the twin-wire components (`voltage2`, `wirefeed2`, `control2`) unused.
fn arcdata(bead: &Bead, arc: &ArcValue) -> String {
    format!(
        "[{},{},{},{},{},{},0,0,0]",
        arc.sched,
        arc.mode,
        super::num(arc.voltage_v, 2),
        bead.wire_feed,
        super::num(arc.control, 2),
        super::num(arc.current_a, 1),
    )
}

/// The `welddata` aggregate of a bead (module docs): weld speed twice, arc data twice.
pub(super) fn welddata(bead: &Bead, arc: &ArcValue) -> String {
    let a = arcdata(bead, arc);
    format!("[{s},{s},{a},{a}]", s = bead.speed)
}

/// The `seamdata` aggregate: ABB's default seamdata with the profile's gas times.
pub(super) fn seamdata(seam: &SeamValue) -> String {
    const UNUSED_ARC: &str = "[0,0,0,0,0,0,0,0,0]";
    let t = |v: f64| super::num(v, 3);
    format!(
        "[{purge},{preflow},{UNUSED_ARC},0,0,0,0,0,{UNUSED_ARC},0,0,{UNUSED_ARC},0.1,0,{UNUSED_ARC},{postflow}]",
        purge = t(seam.purge_s),
        preflow = t(seam.preflow_s),
        postflow = t(seam.postflow_s),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bead(speed: &str, wire_feed: &str) -> Bead {
        Bead {
            speed: speed.into(),
            wire_feed: wire_feed.into(),
        }
    }

    #[test]
    fn welddata_follow_the_robotware_6_layout() {
        let arc = ArcValue {
            sched: 12,
            mode: 1,
            voltage_v: 19.5,
            current_a: 181.5,
            control: -1.0,
        };
        // [weld_speed, org_weld_speed, main_arc, org_arc]; arcdata [sched, mode, voltage,
        // wirefeed, control, current, voltage2, wirefeed2, control2].
        assert_eq!(
            welddata(&bead("7", "5.53"), &arc),
            "[7,7,[12,1,19.5,5.53,-1,181.5,0,0,0],[12,1,19.5,5.53,-1,181.5,0,0,0]]"
        );
    }

    #[test]
    fn seamdata_is_abbs_default_with_the_gas_times() {
        assert_eq!(
            seamdata(&SeamValue::default()),
            "[0.2,0.05,[0,0,0,0,0,0,0,0,0],0,0,0,0,0,[0,0,0,0,0,0,0,0,0],0,0,[0,0,0,0,0,0,0,0,0],0.1,0,[0,0,0,0,0,0,0,0,0],0.05]"
        );
        let s = seamdata(&SeamValue {
            purge_s: 1.0,
            preflow_s: 0.5,
            postflow_s: 2.25,
        });
        // 16 top-level components, 4 of them arcdata of 9.
        assert!(s.starts_with("[1,0.5,[") && s.ends_with("],2.25]"), "{s}");
        assert_eq!(s.matches('[').count(), 5);
        assert_eq!(s.split(',').count(), 12 + 4 * 9);
    }
}
