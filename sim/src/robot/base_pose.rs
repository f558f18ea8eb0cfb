//! Where a robot's root link is in the world: what a scenario traces and a report replays.

use nalgebra::{Isometry3, Rotation3};

/// The pose of the URDF root link in the world after a world step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BasePose {
    /// Position of the root link's origin (m).
    pub position_m: [f64; 3],
    /// Orientation as URDF roll, pitch, yaw (rad): the rotation is
    /// `Rz(yaw) · Ry(pitch) · Rx(roll)`, as a URDF `<origin rpy>` reads.
    pub rpy_rad: [f64; 3],
}

impl Default for BasePose {
    /// At the world origin, upright.
    fn default() -> Self {
        Self {
            position_m: [0.0; 3],
            rpy_rad: [0.0; 3],
        }
    }
}

impl BasePose {
    /// The pose of a rigid transform.
    pub fn of(pose: &Isometry3<f64>) -> Self {
        let t = pose.translation.vector;
        // nalgebra's angles are the URDF convention (extrinsic X, Y, Z); at pitch ±90° it
        // picks one of the many equal decompositions, which still composes to the same pose.
        let (roll, pitch, yaw) = Rotation3::from(pose.rotation).euler_angles();
        Self {
            position_m: [t.x, t.y, t.z],
            rpy_rad: [roll, pitch, yaw],
        }
    }

    /// The same orientation as roll, pitch, yaw nearest to `previous` (a trace's last row):
    /// of the two decompositions every rotation has, `(r, p, y)` and `(r + π, π − p, y + π)`,
    /// each angle moved by whole turns, the one that moved least. A body tipping past 90° of
    /// pitch then reads as a pitch that keeps growing instead of roll and yaw jumping by π.
    pub fn rpy_near(&self, previous: [f64; 3]) -> [f64; 3] {
        use std::f64::consts::{PI, TAU};
        let [r, p, y] = self.rpy_rad;
        let near = |angle: f64, to: f64| angle + TAU * ((to - angle) / TAU).round();
        [[r, p, y], [r + PI, PI - p, y + PI]]
            .into_iter()
            .map(|c| std::array::from_fn(|i| near(c[i], previous[i])))
            .min_by(|a: &[f64; 3], b: &[f64; 3]| {
                let distance = |c: &[f64; 3]| -> f64 {
                    c.iter().zip(&previous).map(|(x, p)| (x - p).powi(2)).sum()
                };
                distance(a).total_cmp(&distance(b))
            })
            .unwrap_or(self.rpy_rad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    #[test]
    fn roll_pitch_yaw_read_back_as_urdf_composes_them() {
        let (roll, pitch, yaw) = (0.3, -0.7, 2.0);
        // URDF order, written out: yaw about Z after pitch about Y after roll about X.
        let rotation = UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), yaw)
            * UnitQuaternion::from_axis_angle(&nalgebra::Vector3::y_axis(), pitch)
            * UnitQuaternion::from_axis_angle(&nalgebra::Vector3::x_axis(), roll);
        let pose = BasePose::of(&Isometry3::from_parts(
            Translation3::new(1.0, -2.0, 0.8),
            rotation,
        ));
        assert_eq!(pose.position_m, [1.0, -2.0, 0.8]);
        for (got, want) in pose.rpy_rad.iter().zip([roll, pitch, yaw]) {
            assert!((got - want).abs() < 1e-12, "{:?}", pose.rpy_rad);
        }
    }

    #[test]
    fn a_body_tipping_past_upright_reads_as_growing_pitch() {
        // Pitched back 110°: the plain decomposition says roll π, pitch -70°, yaw π.
        let rotation = UnitQuaternion::from_axis_angle(&nalgebra::Vector3::y_axis(), -1.92);
        let pose = BasePose::of(&Isometry3::from_parts(Translation3::identity(), rotation));
        assert!(pose.rpy_rad[0].abs() > 3.0, "{:?}", pose.rpy_rad);
        let near = pose.rpy_near([0.0, -1.5, 0.0]);
        for (got, want) in near.iter().zip([0.0, -1.92, 0.0]) {
            assert!((got - want).abs() < 1e-9, "{near:?}");
        }
        // Near a roll of 2π it keeps counting turns.
        let turned = BasePose::default().rpy_near([6.2, 0.0, 0.0]);
        assert!(
            (turned[0] - std::f64::consts::TAU).abs() < 1e-12,
            "{turned:?}"
        );
        let back = UnitQuaternion::from_euler_angles(near[0], near[1], near[2]);
        assert!(back.angle_to(&rotation) < 1e-9);
    }

    #[test]
    fn a_body_on_its_back_composes_back_to_the_same_rotation() {
        // Pitch -90°: roll and yaw are not unique, the rotation they give must be.
        let rotation = UnitQuaternion::from_euler_angles(0.4, -std::f64::consts::FRAC_PI_2, 0.1);
        let pose = BasePose::of(&Isometry3::from_parts(Translation3::identity(), rotation));
        let [r, p, y] = pose.rpy_rad;
        let back = UnitQuaternion::from_euler_angles(r, p, y);
        assert!(back.angle_to(&rotation) < 1e-6, "{:?}", pose.rpy_rad);
    }
}
