//! Motion timing: the placed root and tip face points become carriage moves (projection onto
//! the carriage planes, move durations at the feed, the machine's feed limit, the wire current
//! from the face speed), checked against the machine's travel.

use cell_profiles::MachineProfile;
use nalgebra::Point2;

use crate::kerf::{self, CurrentLimits};
use crate::wing::{move_durations, Towers};

use super::JobError;

/// A run of carriage moves in machine coordinates (mm, mm/s, A). Point k is reached by move
/// k − 1, which lasts max(‖ΔXY‖, ‖ΔUV‖) / `feed_mm_s[k]`; entry 0 repeats entry 1's values.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Motion {
    /// XY carriage positions (root tower).
    pub xy: Vec<Point2<f64>>,
    /// UV carriage positions (tip tower); equal to `xy` on a straight cut.
    pub uv: Vec<Point2<f64>>,
    /// Feed of the carriage that moves farther, per point (mm/s).
    pub feed_mm_s: Vec<f64>,
    /// Wire current per point (A).
    pub current_a: Vec<f64>,
}

impl Motion {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.xy.len()
    }

    /// True without points.
    pub fn is_empty(&self) -> bool {
        self.xy.is_empty()
    }
}

/// Turns placed root/tip face points into carriage moves with feeds and currents.
pub(super) struct Mover {
    pub(super) towers: Towers,
    pub(super) feed_mm_s: f64,
    pub(super) max_feed_mm_s: f64,
    pub(super) schedule: Option<(f64, f64)>,
    pub(super) supply: CurrentLimits,
    pub(super) current_a: f64,
}

impl Mover {
    /// Moves through the placed face points `root`, `tip` (machine XY frame): each lasts long
    /// enough for the faster face to run at the feed times `feed_ratio` of the point it
    /// reaches ([`move_durations`]) and for the faster
    /// carriage to stay within the machine's feed limit; the wire current follows the faster
    /// face's speed (seed 001 constant-kerf schedule).
    pub(super) fn motion(
        &self,
        root: &[Point2<f64>],
        tip: &[Point2<f64>],
        feed_ratio: &[f64],
        notes: &mut Vec<String>,
    ) -> Result<Motion, JobError> {
        let (xy, uv): (Vec<_>, Vec<_>) = root
            .iter()
            .zip(tip)
            .map(|(r, t)| self.towers.project(*r, *t))
            .unzip();
        let mut durations = move_durations(root, tip, self.feed_mm_s);
        // Move k reaches point k + 1 at that point's feed ratio.
        for (d, r) in durations.iter_mut().zip(&feed_ratio[1..]) {
            *d /= r;
        }
        let mut slowed = 0;
        let mut carriage_feed = Vec::with_capacity(durations.len());
        let mut face_speed = Vec::with_capacity(durations.len());
        for (k, d) in durations.iter_mut().enumerate() {
            let carriage = (xy[k + 1] - xy[k]).norm().max((uv[k + 1] - uv[k]).norm());
            if *d > 0.0 && carriage / *d > self.max_feed_mm_s {
                *d = carriage / self.max_feed_mm_s;
                slowed += 1;
            }
            let face = (root[k + 1] - root[k])
                .norm()
                .max((tip[k + 1] - tip[k]).norm());
            if *d > 0.0 {
                carriage_feed.push(carriage / *d);
                face_speed.push(face / *d);
            } else {
                carriage_feed.push(self.feed_mm_s);
                face_speed.push(self.feed_mm_s);
            }
        }
        if slowed > 0 {
            notes.push(format!(
                "{slowed} moves slowed to the machine's feed limit {} mm/s (the carriages move \
                 farther than the foam faces)",
                self.max_feed_mm_s
            ));
        }
        let currents: Vec<f64> = match self.schedule {
            Some((q_eff, r)) => {
                let schedule = kerf::current_schedule(&face_speed, q_eff, r, self.supply)?;
                let clamped = schedule.iter().filter(|s| s.clamped).count();
                if clamped > 0 {
                    notes.push(format!(
                        "{clamped} of {} current set-points clamped to the supply limits \
                         {}..{} A: the kerf deviates there",
                        schedule.len(),
                        self.supply.min_a,
                        self.supply.max_a
                    ));
                }
                schedule.iter().map(|s| s.current_a).collect()
            }
            None => vec![self.current_a; face_speed.len()],
        };
        // Point k is reached by move k − 1; point 0 takes move 0's values.
        let per_point = |v: &[f64]| {
            let mut out = Vec::with_capacity(v.len() + 1);
            out.push(v.first().copied().unwrap_or(self.feed_mm_s));
            out.extend_from_slice(v);
            out
        };
        Ok(Motion {
            xy,
            uv,
            feed_mm_s: per_point(&carriage_feed),
            current_a: per_point(&currents),
        })
    }
}

/// Checks every carriage position of `motion` against the machine's travel.
pub(super) fn check_envelope(
    machine: &MachineProfile,
    four_axis: bool,
    what: &'static str,
    motion: &Motion,
) -> Result<(), JobError> {
    for (k, (xy, uv)) in motion.xy.iter().zip(&motion.uv).enumerate() {
        let mut position = vec![('X', xy.x), ('Y', xy.y)];
        if let (true, Some([u, v])) = (four_axis, machine.second_carriage_axes()) {
            position.extend([(u, uv.x), (v, uv.y)]);
        }
        machine
            .check_position(&position)
            .map_err(|violation| JobError::Envelope {
                what,
                point: k,
                violation,
            })?;
    }
    Ok(())
}
