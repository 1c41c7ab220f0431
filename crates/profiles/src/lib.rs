//! Machine profiles: what a machine in the cell can do, read from `config/machines/*.yaml`.
//!
//! A profile names the machine's axes and their travel, its feed limit and the geometry of its
//! process (for a hot-wire cutter: the tower separation and where the foam block sits). The
//! planner checks its paths against it; the emitter and the bridge read the same file, so one
//! file describes one machine.
//!
//! Every key is checked: an unknown or mistyped key, or a value out of range, is an error that
//! names the file and the field (and the line, for YAML syntax and unknown keys).
//!
//! ```
//! let profile = cell_profiles::MachineProfile::resolve("linuxcnc-xyuv").unwrap();
//! assert!(profile.is_four_axis_hotwire());
//! assert!(profile.check_position(&[('X', 10.0), ('U', 700.0)]).is_err());
//! ```
//!
//! One file per concept: [`machine`] (the profile, its axes and feed limit, loading and the
//! section-by-section check), [`hotwire`] (the towers), [`gcode`] and [`template`] (G-code
//! output), [`rapid`] (ABB RAPID output), [`robot`] (the arm's kinematics for RAPID), [`cutting`] (sheet cutting: kerf table, lead-ins,
//! compensation), [`envelope`] (positions against the travel), [`error`]. Errors have the shape of [`cell_config`]: `FILE[:LINE]: field `PATH`: what`.

pub mod cutting;
pub mod envelope;
pub mod error;
pub mod gcode;
pub mod hotwire;
pub mod machine;
pub mod rapid;
pub mod robot;
pub mod template;

pub use cutting::{
    Compensation, CuttingSection, KerfEntry, LeadIn, LeadShape, MaterialRef, TooSmallHoles,
};
pub use envelope::EnvelopeViolation;
pub use error::ProfileError;
pub use gcode::{
    AxisWords, Dialect, Extrusion, ExtrusionMode, FeedMode, FirmwareMotion, GcodeSettings, Pierce,
    PowerWords, Units,
};
pub use hotwire::HotwireGeometry;
pub use machine::{MachineProfile, Process};
pub use rapid::RapidSettings;
pub use robot::{FrameValue, OpwParameters, RobotSection};
pub use template::TEMPLATE_PLACEHOLDERS;

/// The profiles shipped in `config/machines/`, compiled in: (name, YAML text).
pub const EMBEDDED_PROFILES: &[(&str, &str)] = &[
    (
        "abb-irb1600-rw7-do",
        include_str!("../../../config/machines/abb-irb1600-rw7-do.yaml"),
    ),
    (
        "abb-irb2600-waam",
        include_str!("../../../config/machines/abb-irb2600-waam.yaml"),
    ),
    (
        "grbl-xy",
        include_str!("../../../config/machines/grbl-xy.yaml"),
    ),
    (
        "grbl-xyuv",
        include_str!("../../../config/machines/grbl-xyuv.yaml"),
    ),
    (
        "mach3-xyab",
        include_str!("../../../config/machines/mach3-xyab.yaml"),
    ),
    (
        "linuxcnc-xyuv",
        include_str!("../../../config/machines/linuxcnc-xyuv.yaml"),
    ),
    (
        "grbl-laser",
        include_str!("../../../config/machines/grbl-laser.yaml"),
    ),
    (
        "linuxcnc-plasma",
        include_str!("../../../config/machines/linuxcnc-plasma.yaml"),
    ),
    (
        "marlin-extruder",
        include_str!("../../../config/machines/marlin-extruder.yaml"),
    ),
    (
        "linuxcnc-plasma-3015",
        include_str!("../../../config/machines/linuxcnc-plasma-3015.yaml"),
    ),
    (
        "linuxcnc-plasma-4020",
        include_str!("../../../config/machines/linuxcnc-plasma-4020.yaml"),
    ),
    (
        "linuxcnc-laser-3015",
        include_str!("../../../config/machines/linuxcnc-laser-3015.yaml"),
    ),
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_profiles_load_and_resolve_case_insensitively() {
        for (name, _) in EMBEDDED_PROFILES {
            let p = MachineProfile::resolve(name).unwrap();
            assert_eq!(&p.name, name);
        }
        assert!(MachineProfile::resolve("LINUXCNC-XYUV")
            .unwrap()
            .is_four_axis_hotwire());
        assert!(!MachineProfile::resolve("grbl-xy")
            .unwrap()
            .is_four_axis_hotwire());
        let e = MachineProfile::resolve("nope").unwrap_err();
        assert!(e.to_string().contains("linuxcnc-xyuv"), "{e}");
        let e = MachineProfile::resolve("/nonexistent/m.yaml").unwrap_err();
        assert!(e.to_string().starts_with("/nonexistent/m.yaml"), "{e}");
    }

    #[test]
    fn every_file_in_config_machines_is_embedded() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../config/machines");
        let mut on_disk: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter_map(|n| n.strip_suffix(".yaml").map(String::from))
            .collect();
        on_disk.sort();
        let mut embedded: Vec<String> = EMBEDDED_PROFILES
            .iter()
            .map(|(n, _)| n.to_string())
            .collect();
        embedded.sort();
        assert_eq!(on_disk, embedded);
    }

    fn base() -> String {
        EMBEDDED_PROFILES
            .iter()
            .find(|(n, _)| *n == "linuxcnc-xyuv")
            .unwrap()
            .1
            .to_string()
    }

    #[test]
    fn a_mistyped_key_names_the_key_and_line() {
        let text = base().replace("root_plane_mm:", "root_plane:");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("m.yaml:"), "{msg}");
        assert!(msg.contains("root_plane"), "{msg}");
        assert!(matches!(
            e,
            ProfileError::Parse(cell_config::ParseError { line: Some(_), .. })
        ));
    }

    #[test]
    fn out_of_range_values_name_the_field() {
        for (from, to, field) in [
            (
                "tower_separation_mm: 1000.0",
                "tower_separation_mm: -1",
                "hotwire.tower_separation_mm",
            ),
            (
                "root_plane_mm: 200.0",
                "root_plane_mm: 1200.0",
                "hotwire.root_plane_mm",
            ),
            ("X: [0.0, 600.0]", "X: [600.0, 0.0]", "axes.X"),
            ("max_feed_mm_s: 25.0", "max_feed_mm_s: 0", "max_feed_mm_s"),
            (
                "supply_a: [0.0, 10.0]",
                "supply_a: [5.0, 1.0]",
                "hotwire.supply_a",
            ),
            ("  V: [0.0, 300.0]\n", "", "axes"),
        ] {
            let text = base().replace(from, to);
            assert_ne!(text, base(), "{from}");
            let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
            assert!(
                matches!(&e, ProfileError::Invalid { field: f, .. } if f == field),
                "{from}: {e}"
            );
        }
        let text = base().replace("process: hotwire", "process: waam");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        assert!(e.to_string().contains("hotwire"), "{e}");
    }

    #[test]
    fn gcode_sections_are_checked_against_the_axes() {
        let p = MachineProfile::resolve("linuxcnc-xyuv").unwrap();
        let g = p.gcode.as_ref().unwrap();
        assert_eq!(
            (g.dialect, g.feed_mode),
            (Dialect::Linuxcnc, FeedMode::InverseTime)
        );
        let text = base().replace("u: U, v: V", "u: W, v: V");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        assert!(
            e.to_string()
                .contains("field `gcode.axis_words`: the second carriage is on U V"),
            "{e}"
        );
        let text = base().replace("u: U, v: V", "u: U");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        assert!(e.to_string().contains("field `gcode.axis_words`:"), "{e}");
        let text = base().replace("feed_mode: inverse_time", "feed_mode: inverse");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        assert!(e.to_string().contains("feed_mode"), "{e}");
    }

    fn embedded(name: &str) -> String {
        EMBEDDED_PROFILES
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap()
            .1
            .to_string()
    }

    #[test]
    fn process_settings_are_checked_and_name_their_field() {
        for (profile, from, to, field) in [
            (
                "linuxcnc-plasma",
                "program_start: [\"G64 P0.05\"]",
                "program_start: [\"G64 P0.05\", \"G91\"]",
                "gcode.program_start[1]",
            ),
            (
                "linuxcnc-plasma",
                "program_start: [\"G64 P0.05\"]",
                "program_start: [\"(job {jobid})\"]",
                "gcode.program_start[0]",
            ),
            ("linuxcnc-plasma", "z_pierce_mm: 3.8, ", "", "gcode.pierce"),
            (
                "linuxcnc-plasma",
                "z_travel_mm: 10.0",
                "z_travel_mm: 150.0",
                "gcode.pierce.z_travel_mm",
            ),
            (
                "grbl-laser",
                "arc_tolerance_mm: 0.01",
                "arc_tolerance_mm: 0",
                "gcode.arc_tolerance_mm",
            ),
            (
                "linuxcnc-xyuv",
                "preheat_dwell_s: 2.0",
                "preheat_dwell_s: 2.0\n  arc_tolerance_mm: 0.01",
                "gcode.arc_tolerance_mm",
            ),
            (
                "marlin-extruder",
                "feed_mode: units_per_minute",
                "feed_mode: inverse_time",
                "gcode.feed_mode",
            ),
            (
                "marlin-extruder",
                "filament_diameter_mm: 1.75",
                "filament_diameter_mm: -1.75",
                "gcode.extrusion.filament_diameter_mm",
            ),
            (
                "marlin-extruder",
                "junction_deviation_mm: 0.013",
                "junction_deviation_mm: 0",
                "gcode.extrusion.motion.junction_deviation_mm",
            ),
            (
                "marlin-extruder",
                "block_buffer_size: 16",
                "block_buffer_size: 1",
                "gcode.extrusion.motion.block_buffer_size",
            ),
            (
                "marlin-extruder",
                "  arc_tolerance_mm: 0.01",
                "  arc_tolerance_mm: 0.01\n  power: {on: M3, off: M5, s_per_unit: 1.0}",
                "gcode.extrusion",
            ),
            ("mach3-xyab", "uv_axes: [A, B]", "uv_axes: [A, C]", "axes"),
        ] {
            let text = embedded(profile).replace(from, to);
            assert_ne!(text, embedded(profile), "{from}");
            let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
            assert!(
                matches!(&e, ProfileError::Invalid { field: f, .. } if f == field),
                "{profile} {to}: {e}"
            );
        }
        // Placeholders and the arc-centre mode word are fine in templates; G91 inside a comment too.
        let text = embedded("linuxcnc-plasma").replace(
            "program_start: [\"G64 P0.05\"]",
            "program_start: [\"(job {job} on {profile}, not G91)\", \"G91.1\"]",
        );
        MachineProfile::from_yaml_str(&text, "m.yaml").unwrap();
        // A mistyped key in a nested section names it with its line.
        let text = embedded("marlin-extruder").replace("retract_mm:", "retract:");
        let e = MachineProfile::from_yaml_str(&text, "m.yaml").unwrap_err();
        assert!(
            matches!(
                e,
                ProfileError::Parse(cell_config::ParseError { line: Some(_), .. })
            ),
            "{e}"
        );
        assert!(e.to_string().contains("retract"), "{e}");
    }

    #[test]
    fn envelope_check_names_the_axis() {
        let p = MachineProfile::resolve("linuxcnc-xyuv").unwrap();
        assert!(p
            .check_position(&[('X', 0.0), ('Y', 300.0), ('U', 600.0), ('V', 0.0)])
            .is_ok());
        let e = p.check_position(&[('X', 10.0), ('V', -0.5)]).unwrap_err();
        assert_eq!((e.axis, e.value), ('V', -0.5));
        assert!(e.to_string().contains("V = -0.500"), "{e}");
        assert!(p.check_position(&[('Z', 1.0)]).is_err());
        assert!(p.check_position(&[('X', f64::NAN)]).is_err());
    }
}
