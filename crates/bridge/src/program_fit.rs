//! Whether a `MachineProgram` is for a G-code controller: its dialect, its machine profile and
//! its file count. One check for every G-code controller kind (GRBL, Marlin); the node's access
//! rule 4 ([`profile_refusal`] with [`UnnamedProfile::Refuse`]) is the same check made strict.

use cell_msgs::MachineProgram;

/// What a program that names no machine profile means for a controller that has one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnnamedProfile {
    /// It could be for any machine: run it (`cell stream` of a file written by hand).
    Allow,
    /// It could be for any machine: refuse it (goals from the network, access rule 4).
    Refuse,
}

/// Why a controller `id` configured for `configured` (empty: any) must not run `program`.
pub fn profile_refusal(
    id: &str,
    configured: &str,
    program: &MachineProgram,
    unnamed: UnnamedProfile,
) -> Option<String> {
    let named = &program.machine_profile;
    let fits = configured.is_empty()
        || named.eq_ignore_ascii_case(configured)
        || (named.is_empty() && unnamed == UnnamedProfile::Allow);
    (!fits).then(|| {
        format!("controller {id} runs machine profile {configured}; the program is for {named:?}")
    })
}

/// Why controller `id`, which speaks `dialect` (`grbl`, `marlin`) and is configured for
/// `configured`, cannot run `program`: another dialect, another machine profile (a program
/// naming none is allowed), or not exactly one file. `None`: it can.
pub(crate) fn gcode_refusal(
    id: &str,
    dialect: &str,
    configured: &str,
    program: &MachineProgram,
) -> Option<String> {
    if program.dialect != dialect {
        return Some(format!(
            "controller {id} speaks {dialect}; the program is in the {:?} dialect (emit it for a \
             {dialect} profile)",
            program.dialect
        ));
    }
    if let Some(why) = profile_refusal(id, configured, program, UnnamedProfile::Allow) {
        return Some(why);
    }
    (program.files.len() != 1).then(|| {
        format!(
            "a G-code program is one file; this one has {}",
            program.files.len()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use cell_msgs::ProgramFile;

    fn program(dialect: &str, profile: &str, files: usize) -> MachineProgram {
        MachineProgram {
            dialect: dialect.into(),
            machine_profile: profile.into(),
            files: (0..files)
                .map(|i| ProgramFile {
                    name: format!("{i}.gcode"),
                    text: "G1 X1\n".into(),
                })
                .collect(),
            ..Default::default()
        }
    }

    #[test]
    fn dialect_profile_and_file_count_each_refuse() {
        let ok = program("marlin", "marlin-extruder", 1);
        assert_eq!(gcode_refusal("p", "marlin", "marlin-extruder", &ok), None);
        assert_eq!(gcode_refusal("p", "marlin", "", &ok), None);
        let why = gcode_refusal("p", "grbl", "", &ok).unwrap();
        assert!(
            why.contains("speaks grbl") && why.contains("\"marlin\""),
            "{why}"
        );
        let other = program("marlin", "prusa", 1);
        let why = gcode_refusal("p", "marlin", "marlin-extruder", &other).unwrap();
        assert!(
            why.contains("marlin-extruder") && why.contains("prusa"),
            "{why}"
        );
        let two = program("marlin", "marlin-extruder", 2);
        assert!(gcode_refusal("p", "marlin", "", &two)
            .unwrap()
            .contains("has 2"));
    }

    #[test]
    fn a_program_naming_no_profile_is_allowed_or_refused_as_asked() {
        let unnamed = program("grbl", "", 1);
        assert_eq!(gcode_refusal("g", "grbl", "grbl-xy", &unnamed), None);
        let why = profile_refusal("g", "grbl-xy", &unnamed, UnnamedProfile::Refuse).unwrap();
        assert!(why.contains("grbl-xy") && why.contains("\"\""), "{why}");
        assert_eq!(
            profile_refusal("g", "", &unnamed, UnnamedProfile::Refuse),
            None
        );
        let upper = program("grbl", "GRBL-XY", 1);
        assert_eq!(
            profile_refusal("g", "grbl-xy", &upper, UnnamedProfile::Refuse),
            None
        );
    }
}
