//! Step 2 of a line: its G and M commands, checked one per modal group (`error:21` on a second
//! command of a group; group numbers as in GRBL's `gc_execute_line`), applied to a copy of the
//! modal state. Non-modal commands (G4, G10, G28, G30, G53, G92, G92.1) are noted for step 3.

use super::code::*;
use super::lex::Words;
use super::{Action, Modal, MotionMode, Spindle};

/// The non-modal command of a line (modal group 0), other than G53.
#[derive(Debug, PartialEq, Clone, Copy)]
pub(super) enum NonModal {
    None,
    Dwell,
    SetCoord,
    Home(u8),
    G92,
    G92Reset,
}

/// What the G and M commands of a line do.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Groups {
    /// The modal state with the line's modal commands applied (values and motion not yet).
    pub new: Modal,
    /// The line's non-modal command.
    pub non_modal: NonModal,
    /// G53: this line's target is in machine coordinates.
    pub absolute_override: bool,
    /// The line names a motion mode (G0–G3, G80).
    pub explicit_motion: bool,
    /// Synchronisation, pause and program end from the M commands (no moves yet).
    pub action: Action,
}

/// Checks and applies the G and M commands of `words` to `modal`. `jog` allows only what a
/// `$J=` line may hold (G20/G21, G90/G91, G53, G93/G94; `error:16` otherwise) and sets linear
/// motion.
pub(super) fn check(modal: &Modal, words: &Words, jog: bool) -> Result<Groups, u8> {
    let (gs, ms) = (&words.gs, &words.ms);
    let mut new = modal.clone();
    let mut groups_seen = [false; 16];
    let mut seen = |g: usize| -> Result<(), u8> {
        if groups_seen[g] {
            Err(MODAL_GROUP_VIOLATION)
        } else {
            groups_seen[g] = true;
            Ok(())
        }
    };
    let mut non_modal = NonModal::None;
    let mut absolute_override = false; // G53
    let mut explicit_motion = false;
    for &(g, mantissa) in gs {
        match (g, mantissa) {
            (0..=3, 0) | (80, 0) => {
                seen(1)?;
                explicit_motion = true;
                new.motion = match g {
                    0 => MotionMode::Rapid,
                    1 => MotionMode::Linear,
                    2 => MotionMode::ArcCw,
                    3 => MotionMode::ArcCcw,
                    _ => MotionMode::Cancel,
                };
            }
            (4, 0) | (10, 0) | (28, 0) | (30, 0) | (92, 0) | (92, 10) | (53, 0) => {
                seen(0)?;
                match (g, mantissa) {
                    (4, _) => non_modal = NonModal::Dwell,
                    (10, _) => non_modal = NonModal::SetCoord,
                    (28, _) => non_modal = NonModal::Home(28),
                    (30, _) => non_modal = NonModal::Home(30),
                    (92, 0) => non_modal = NonModal::G92,
                    (92, _) => non_modal = NonModal::G92Reset,
                    _ => absolute_override = true,
                }
            }
            (17..=19, 0) => {
                seen(2)?;
                new.plane = (g - 17) as u8;
            }
            (90, 0) | (91, 0) => {
                seen(3)?;
                new.incremental = g == 91;
            }
            (91, 10) => seen(4)?,
            (93, 0) | (94, 0) => {
                seen(5)?;
                new.inverse_time = g == 93;
            }
            (20, 0) | (21, 0) => {
                seen(6)?;
                new.inches = g == 20;
            }
            (40, 0) => seen(7)?,
            (43, 10) | (49, 0) => seen(8)?,
            (54..=59, 0) => {
                seen(12)?;
                new.coord = (g - 54) as usize;
            }
            (59, _) => return Err(UNSUPPORTED_COORD_SYS),
            (61, 0) => seen(13)?,
            _ => return Err(UNSUPPORTED_COMMAND),
        }
    }
    let mut action = Action::default();
    for &(m, _) in ms {
        match m {
            0 | 1 | 2 | 30 => {
                seen(9)?;
                action.sync = true;
                if m <= 1 {
                    action.pause = true;
                } else {
                    action.program_end = true;
                }
            }
            3..=5 => {
                seen(10)?;
                let s = match m {
                    3 => Spindle::Cw,
                    4 => Spindle::Ccw,
                    _ => Spindle::Off,
                };
                if s != new.spindle {
                    action.sync = true;
                }
                new.spindle = s;
            }
            7..=9 => {
                seen(11)?;
                match m {
                    7 => new.mist = true,
                    8 => new.flood = true,
                    _ => {
                        new.mist = false;
                        new.flood = false;
                    }
                }
                action.sync = true;
            }
            _ => return Err(UNSUPPORTED_COMMAND),
        }
    }
    if jog {
        let allowed = non_modal == NonModal::None
            && !explicit_motion
            && ms.is_empty()
            && gs.iter().all(|g| {
                matches!(
                    g,
                    (20, 0) | (21, 0) | (90, 0) | (91, 0) | (53, 0) | (93..=94, 0)
                )
            });
        if !allowed {
            return Err(16); // Invalid jog command
        }
        new.motion = MotionMode::Linear;
    }
    Ok(Groups {
        new,
        non_modal,
        absolute_override,
        explicit_motion,
        action,
    })
}
