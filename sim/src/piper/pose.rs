//! End poses as the firmware sees them: flange pose from its DH model (spec §12) and the
//! RX/RY/RZ Euler convention of the wire (R = Rz·Ry·Rx, spec §3).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// A pose on the wire: position (m) and extrinsic XYZ Euler angles (rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WirePose {
    /// X, Y, Z in metres.
    pub position_m: [f64; 3],
    /// RX, RY, RZ in radians (R = Rz(RZ)·Ry(RY)·Rx(RX)).
    pub euler_rad: [f64; 3],
}

impl WirePose {
    /// The rigid transform.
    pub fn to_isometry(&self) -> Isometry3<f64> {
        let [rx, ry, rz] = self.euler_rad;
        Isometry3::from_parts(
            Translation3::new(self.position_m[0], self.position_m[1], self.position_m[2]),
            UnitQuaternion::from_euler_angles(rx, ry, rz),
        )
    }

    /// From a rigid transform (Euler extraction as the SDK FK does it).
    pub fn from_isometry(iso: &Isometry3<f64>) -> Self {
        let m = iso.rotation.to_rotation_matrix();
        let r = m.matrix();
        let roll = r[(2, 1)].atan2(r[(2, 2)]);
        let pitch = (-r[(2, 0)]).atan2((r[(0, 0)].powi(2) + r[(1, 0)].powi(2)).sqrt());
        let yaw = r[(1, 0)].atan2(r[(0, 0)]);
        let t = iso.translation.vector;
        Self {
            position_m: [t.x, t.y, t.z],
            euler_rad: [roll, pitch, yaw],
        }
    }

    /// From the wire's integers: µm and m°.
    pub fn from_wire(v: [i32; 6]) -> Self {
        Self {
            position_m: [
                f64::from(v[0]) * 1e-6,
                f64::from(v[1]) * 1e-6,
                f64::from(v[2]) * 1e-6,
            ],
            euler_rad: [
                (f64::from(v[3]) / 1000.0).to_radians(),
                (f64::from(v[4]) / 1000.0).to_radians(),
                (f64::from(v[5]) / 1000.0).to_radians(),
            ],
        }
    }

    /// To the wire's integers: µm and m°, rounded and saturated.
    pub fn to_wire(&self) -> [i32; 6] {
        use crate::piper::codec::arm::{rad_to_mdeg, sat_i32};
        [
            sat_i32((self.position_m[0] * 1e6).round()),
            sat_i32((self.position_m[1] * 1e6).round()),
            sat_i32((self.position_m[2] * 1e6).round()),
            rad_to_mdeg(self.euler_rad[0]),
            rad_to_mdeg(self.euler_rad[1]),
            rad_to_mdeg(self.euler_rad[2]),
        ]
    }
}

/// Position error (m) and rotation error (rad) between two poses.
pub fn pose_error(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    let dp: Vector3<f64> = a.translation.vector - b.translation.vector;
    (dp.norm(), a.rotation.angle_to(&b.rotation))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_round_trip_and_wire_scaling() {
        let p = WirePose {
            position_m: [0.056128, 0.0, 0.213266],
            euler_rad: [0.1, 85f64.to_radians(), -0.3],
        };
        let back = WirePose::from_isometry(&p.to_isometry());
        for i in 0..3 {
            assert!((back.euler_rad[i] - p.euler_rad[i]).abs() < 1e-9);
        }
        assert_eq!(p.to_wire()[0], 56128);
        assert_eq!(p.to_wire()[4], 85000);
        let w = WirePose::from_wire(p.to_wire());
        assert!((w.position_m[2] - 0.213266).abs() < 1e-12);
    }
}
