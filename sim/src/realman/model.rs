//! Kinematic and dynamic data of the Realman arms the emulator can be: the modified-DH table,
//! the flange length, joint ranges, speeds and link masses (`docs/protocols/realman.md` §13).
//!
//! The MDH convention is Craig's: frame i follows frame i−1 by
//! `RotX(α_{i−1})·TransX(a_{i−1})·RotZ(q_i + offset_i)·TransZ(d_i)`; the flange is a further
//! `TransZ(flange_d)` on the last frame. Joint angles are the controller's readings; the MDH
//! offset is added to them.

/// One row of a modified-DH table (Craig convention, see the module docs): the one MDH row
/// type of the emulators, shared with the Piper.
pub use crate::kinematics::MdhRow;

/// One Realman arm model: what the controller's kinematics, planner and the physics plant need.
///
/// Vectors have one entry per joint (`dof` entries), joint 1 first.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmModel {
    /// Product name as the controller reports it, e.g. `"RM65-B"`.
    pub name: String,
    /// Number of joints (6 for RM65, 7 for RM75).
    pub dof: usize,
    /// The MDH table, one row per joint; the last row's d is 0 (the flange is `flange_d_m`).
    pub mdh: Vec<MdhRow>,
    /// Distance from the last joint frame to the flange along its Z axis, m
    /// (144 mm on the -B variants, 172.5 mm with the 6-axis force sensor, -6F).
    pub flange_d_m: f64,
    /// Lower joint limits, ° (controller soft limits at power-on).
    pub joint_min_deg: Vec<f64>,
    /// Upper joint limits, °.
    pub joint_max_deg: Vec<f64>,
    /// Maximum joint speeds, °/s (spec sheet).
    pub max_speed_deg_s: Vec<f64>,
    /// Maximum joint accelerations, °/s². No vendor default is published; we use 3 × the
    /// speed (the doc asks for acc/speed ≥ 1.5 and caps acc at 500 RPM/s = 3000 °/s²).
    pub max_acc_deg_s2: Vec<f64>,
    /// Link masses (links 1..dof), kg, from the vendor's CAD table.
    pub link_masses_kg: Vec<f64>,
}

/// Acceleration limit = this × speed limit (see [`ArmModel::max_acc_deg_s2`]).
const ACC_PER_SPEED_1_S: f64 = 3.0;

impl ArmModel {
    /// RM65-B: 6 joints, flange d 144 mm, reach 610 mm (§13).
    pub fn rm65b() -> Self {
        let mdh = vec![
            MdhRow::from_mm_deg(0.0, 0.0, 240.5, 0.0),
            MdhRow::from_mm_deg(0.0, 90.0, 0.0, 90.0),
            MdhRow::from_mm_deg(256.0, 0.0, 0.0, 90.0),
            MdhRow::from_mm_deg(0.0, 90.0, 210.0, 0.0),
            MdhRow::from_mm_deg(0.0, -90.0, 0.0, 0.0),
            MdhRow::from_mm_deg(0.0, 90.0, 0.0, 0.0),
        ];
        let speed = vec![180.0, 180.0, 225.0, 225.0, 225.0, 225.0];
        Self {
            name: "RM65-B".to_owned(),
            dof: 6,
            mdh,
            flange_d_m: 0.144,
            joint_min_deg: vec![-178.0, -130.0, -135.0, -178.0, -128.0, -360.0],
            joint_max_deg: vec![178.0, 130.0, 135.0, 178.0, 128.0, 360.0],
            max_acc_deg_s2: speed.iter().map(|v| v * ACC_PER_SPEED_1_S).collect(),
            max_speed_deg_s: speed,
            link_masses_kg: vec![1.51, 1.653, 0.726, 0.671, 0.647, 0.107],
        }
    }

    /// RM75-B: 7 joints, flange d 144 mm (§13).
    pub fn rm75b() -> Self {
        let mdh = vec![
            MdhRow::from_mm_deg(0.0, 0.0, 240.5, 0.0),
            MdhRow::from_mm_deg(0.0, -90.0, 0.0, 0.0),
            MdhRow::from_mm_deg(0.0, 90.0, 256.0, 0.0),
            MdhRow::from_mm_deg(0.0, -90.0, 0.0, 0.0),
            MdhRow::from_mm_deg(0.0, 90.0, 210.0, 0.0),
            MdhRow::from_mm_deg(0.0, -90.0, 0.0, 0.0),
            MdhRow::from_mm_deg(0.0, 90.0, 0.0, 0.0),
        ];
        let speed = vec![180.0, 180.0, 225.0, 225.0, 225.0, 225.0, 225.0];
        Self {
            name: "RM75-B".to_owned(),
            dof: 7,
            mdh,
            flange_d_m: 0.144,
            joint_min_deg: vec![-178.0, -130.0, -178.0, -135.0, -178.0, -128.0, -360.0],
            joint_max_deg: vec![178.0, 130.0, 178.0, 135.0, 178.0, 128.0, 360.0],
            max_acc_deg_s2: speed.iter().map(|v| v * ACC_PER_SPEED_1_S).collect(),
            max_speed_deg_s: speed,
            link_masses_kg: vec![1.574, 1.217, 1.11, 0.685, 0.619, 0.602, 0.107],
        }
    }

    /// The model for a product name (case-insensitive): `RM65-B`, `RM65-6F`, `RM75-B`,
    /// `RM75-6F`, or the bare `RM65` / `RM75` (= -B). The -6F variants carry the 6-axis force
    /// sensor: flange d 172.5 mm and 0.248 kg more on the last link.
    pub fn from_product(product: &str) -> Option<Self> {
        let upper = product.trim().to_ascii_uppercase();
        let with_sensor = |mut m: Self, name: &str| {
            m.name = name.to_owned();
            m.flange_d_m = 0.1725;
            if let Some(last) = m.link_masses_kg.last_mut() {
                *last += 0.248;
            }
            m
        };
        match upper.as_str() {
            "RM65-B" | "RM65" => Some(Self::rm65b()),
            "RM75-B" | "RM75" => Some(Self::rm75b()),
            "RM65-6F" => Some(with_sensor(Self::rm65b(), "RM65-6F")),
            "RM75-6F" => Some(with_sensor(Self::rm75b(), "RM75-6F")),
            _ => None,
        }
    }

    /// Lower joint limits, rad.
    pub fn joint_min_rad(&self) -> Vec<f64> {
        self.joint_min_deg.iter().map(|d| d.to_radians()).collect()
    }

    /// Upper joint limits, rad.
    pub fn joint_max_rad(&self) -> Vec<f64> {
        self.joint_max_deg.iter().map(|d| d.to_radians()).collect()
    }

    /// Maximum joint speeds, rad/s.
    pub fn max_speed_rad_s(&self) -> Vec<f64> {
        self.max_speed_deg_s
            .iter()
            .map(|d| d.to_radians())
            .collect()
    }

    /// Maximum joint accelerations, rad/s².
    pub fn max_acc_rad_s2(&self) -> Vec<f64> {
        self.max_acc_deg_s2.iter().map(|d| d.to_radians()).collect()
    }

    /// Reach of the flange from the shoulder (J2 axis), m: the sum of the link lengths after
    /// joint 1. A flange target farther than this from the shoulder is unreachable.
    pub fn reach_m(&self) -> f64 {
        let links: f64 = self.mdh[1..]
            .iter()
            .map(|r| r.a_m.abs() + r.d_m.abs())
            .sum();
        links + self.flange_d_m
    }

    /// Height of the shoulder (first joint's d) above the base, m.
    pub fn shoulder_height_m(&self) -> f64 {
        self.mdh.first().map_or(0.0, |r| r.d_m)
    }

    /// Whether `joints_rad` (length `dof`) lies within the joint limits; the index of the first
    /// joint outside them otherwise.
    pub fn first_out_of_limits(&self, joints_rad: &[f64]) -> Option<usize> {
        joints_rad.iter().enumerate().find_map(|(i, q)| {
            let deg = q.to_degrees();
            let lo = self
                .joint_min_deg
                .get(i)
                .copied()
                .unwrap_or(f64::NEG_INFINITY);
            let hi = self.joint_max_deg.get(i).copied().unwrap_or(f64::INFINITY);
            // A hair of tolerance: values converted from 0.001° integers sit exactly on limits.
            (!(deg >= lo - 1e-9 && deg <= hi + 1e-9)).then_some(i)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_have_one_entry_per_joint() {
        for m in [ArmModel::rm65b(), ArmModel::rm75b()] {
            for len in [
                m.mdh.len(),
                m.joint_min_deg.len(),
                m.joint_max_deg.len(),
                m.max_speed_deg_s.len(),
                m.max_acc_deg_s2.len(),
                m.link_masses_kg.len(),
            ] {
                assert_eq!(len, m.dof, "{}", m.name);
            }
        }
    }

    #[test]
    fn products_resolve() {
        assert_eq!(ArmModel::from_product("rm65-b"), Some(ArmModel::rm65b()));
        let f = ArmModel::from_product("RM65-6F").expect("6F");
        assert!((f.flange_d_m - 0.1725).abs() < 1e-12);
        assert_eq!(ArmModel::from_product("RM75").map(|m| m.dof), Some(7));
        assert_eq!(ArmModel::from_product("GEN72"), None);
        // RM65 reach: 256 + 210 + 144 mm.
        assert!((ArmModel::rm65b().reach_m() - 0.610).abs() < 1e-12);
    }
}
