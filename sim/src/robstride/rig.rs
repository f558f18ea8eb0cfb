//! The test rig: one motor on a fixed base driving a load (spec-independent plant model).
//!
//! The motor's output shaft turns about a horizontal axis (joint axis Y, gravity −Z), so a
//! pendulum swings in the X–Z plane. Angle 0 = the
//! pendulum hanging straight down; at ±π/2 it is horizontal and gravity loads the motor with
//! m·g·l. The same rig is written as URDF by [`rig_urdf`] (`urdf/robstride_rig.urdf` is its
//! default instance); the emulator integrates it directly ([`RigPlant`]) so the inner control
//! loops can run at 10 kHz like firmware does, which a 1 kHz world step could not hold stable.

use serde::{Deserialize, Serialize};

/// Standard gravity (m/s²).
pub const GRAVITY_M_S2: f64 = 9.80665;

/// What the motor drives.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Load {
    /// Nothing: only the rotor's reflected inertia.
    None,
    /// A uniform disc centred on the axis (no gravity torque).
    Disc {
        /// Disc mass (kg).
        mass_kg: f64,
        /// Disc radius (m).
        radius_m: f64,
    },
    /// A point mass on a massless arm (gravity torque m·g·l·sin θ).
    Pendulum {
        /// Mass at the end of the arm (kg).
        mass_kg: f64,
        /// Arm length, axis to mass (m).
        length_m: f64,
    },
}

impl Default for Load {
    fn default() -> Self {
        Load::Disc {
            mass_kg: 1.0,
            radius_m: 0.1,
        }
    }
}

impl Load {
    /// The load's inertia about the motor axis (kg·m²).
    pub fn inertia_kg_m2(self) -> f64 {
        match self {
            Load::None => 0.0,
            Load::Disc { mass_kg, radius_m } => 0.5 * mass_kg * radius_m * radius_m,
            Load::Pendulum { mass_kg, length_m } => mass_kg * length_m * length_m,
        }
    }

    /// Gravity torque on the shaft at `angle_rad` (angle 0 = hanging down).
    pub fn gravity_torque_nm(self, angle_rad: f64) -> f64 {
        match self {
            Load::Pendulum { mass_kg, length_m } => {
                -mass_kg * GRAVITY_M_S2 * length_m * angle_rad.sin()
            }
            _ => 0.0,
        }
    }
}

/// `torque_nm`, or zero when it is not finite: a NaN torque from a broken command or a
/// diverged model must not reach the physics.
pub fn finite_or_zero(torque_nm: f64) -> f64 {
    if torque_nm.is_finite() {
        torque_nm
    } else {
        0.0
    }
}

/// A single-axis plant the motor drives: the actuator contract's shaft, under the name this
/// module has always used.
pub use crate::actuator::ShaftPlant as Plant;

/// The rig integrated directly (semi-implicit Euler).
#[derive(Debug, Clone, PartialEq)]
pub struct RigPlant {
    load: Load,
    inertia_kg_m2: f64,
    friction_nm_s_per_rad: f64,
    position_rad: f64,
    velocity_rad_s: f64,
    external_nm: f64,
}

impl RigPlant {
    /// A rig with the given load, rotor inertia, viscous friction and start angle.
    pub fn new(
        load: Load,
        rotor_inertia_kg_m2: f64,
        friction_nm_s_per_rad: f64,
        start_rad: f64,
    ) -> Self {
        Self {
            load,
            inertia_kg_m2: (rotor_inertia_kg_m2 + load.inertia_kg_m2()).max(1e-6),
            friction_nm_s_per_rad: friction_nm_s_per_rad.max(0.0),
            position_rad: start_rad,
            velocity_rad_s: 0.0,
            external_nm: 0.0,
        }
    }
}

impl Plant for RigPlant {
    fn step(&mut self, torque_nm: f64, dt_s: f64) {
        let gravity = self.load.gravity_torque_nm(self.position_rad);
        let driving = torque_nm + gravity + self.external_nm;
        // Friction treated implicitly so a large coefficient cannot make the step unstable.
        let j = self.inertia_kg_m2;
        let b = self.friction_nm_s_per_rad;
        let velocity = (j * self.velocity_rad_s + dt_s * driving) / (j + dt_s * b);
        let position = self.position_rad + velocity * dt_s;
        // An absurd load (validation bounds it, but the library takes any f64) can overflow
        // to inf/NaN; the shaft then stalls where it is rather than reporting NaN.
        if velocity.is_finite() && position.is_finite() {
            self.velocity_rad_s = velocity;
            self.position_rad = position;
        } else {
            self.velocity_rad_s = 0.0;
        }
    }

    fn position_rad(&self) -> f64 {
        self.position_rad
    }

    fn velocity_rad_s(&self) -> f64 {
        self.velocity_rad_s
    }

    fn inertia_kg_m2(&self) -> f64 {
        self.inertia_kg_m2
    }

    fn set_external_torque_nm(&mut self, torque_nm: f64) {
        self.external_nm = finite_or_zero(torque_nm);
    }
}

/// The rig as URDF text: a fixed base, a revolute joint `motor` about Y, and the load link.
/// The pendulum is a thin rod of negligible mass with a point-like sphere at its end; the disc
/// a cylinder whose axis is the joint axis.
pub fn rig_urdf(load: Load, peak_torque_nm: f64, max_speed_rad_s: f64) -> String {
    rig_urdf_with_rotor(load, 0.0, peak_torque_nm, max_speed_rad_s)
}

/// [`rig_urdf`] with the rotor's reflected inertia added to the load link about the joint axis
/// (URDF has no armature; this is how the physics world sees the rotor).
pub fn rig_urdf_with_rotor(
    load: Load,
    rotor_inertia_kg_m2: f64,
    peak_torque_nm: f64,
    max_speed_rad_s: f64,
) -> String {
    let rotor = rotor_inertia_kg_m2.max(0.0);
    let load_link = match load {
        Load::None => inertial_block(0.001, [0.0, 0.0, 0.0], [1e-6, 1e-6 + rotor, 1e-6], ""),
        Load::Disc { mass_kg, radius_m } => {
            let axial = 0.5 * mass_kg * radius_m * radius_m;
            let thickness = 0.02;
            let radial = mass_kg * (3.0 * radius_m * radius_m + thickness * thickness) / 12.0;
            inertial_block(
                mass_kg,
                [0.0, 0.0, 0.0],
                [radial, axial + rotor, radial],
                &format!(
                    "<collision><origin rpy=\"1.5707963 0 0\"/><geometry><cylinder radius=\"{radius_m}\" length=\"{thickness}\"/></geometry></collision>"
                ),
            )
        }
        Load::Pendulum { mass_kg, length_m } => {
            // A point mass: its own inertia is tiny; the parallel-axis term comes from the
            // COM offset, which the physics engine adds itself.
            let own = 1e-6_f64.max(mass_kg * 1e-5);
            inertial_block(
                mass_kg,
                [0.0, 0.0, -length_m],
                [own, own + rotor, own],
                &format!(
                    "<collision><origin xyz=\"0 0 {z}\"/><geometry><sphere radius=\"0.02\"/></geometry></collision>",
                    z = -length_m
                ),
            )
        }
    };
    format!(
        r#"<?xml version="1.0"?>
<!-- Generated by sim::robstride::rig::rig_urdf; see urdf/README.md. -->
<robot name="robstride_rig">
  <link name="base">
    <inertial><origin xyz="0 0 0"/><mass value="5.0"/><inertia ixx="0.05" iyy="0.05" izz="0.05" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="load">
    {load_link}
  </link>
  <joint name="motor" type="continuous">
    <parent link="base"/>
    <child link="load"/>
    <origin xyz="0 0 0.5" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>
    <limit effort="{peak_torque_nm}" velocity="{max_speed_rad_s}"/>
  </joint>
</robot>
"#
    )
}

fn inertial_block(mass_kg: f64, com: [f64; 3], diag: [f64; 3], extra: &str) -> String {
    format!(
        "<inertial><origin xyz=\"{} {} {}\"/><mass value=\"{mass_kg}\"/><inertia ixx=\"{}\" iyy=\"{}\" izz=\"{}\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>{extra}",
        com[0], com[1], com[2], diag[0], diag[1], diag[2]
    )
}

/// The rig in the shared physics world (`sim::physics::RapierWorld`, rapier3d), loaded from
/// [`rig_urdf_with_rotor`]. The world's step must equal the controller's substep (100 µs).
pub struct WorldPlant {
    world: crate::physics::RapierWorld,
    inertia_kg_m2: f64,
    friction_nm_s_per_rad: f64,
    external_nm: f64,
}

impl WorldPlant {
    /// Build the rig world with a fixed step of `step_s` starting at `start_rad`.
    pub fn new(
        load: Load,
        rotor_inertia_kg_m2: f64,
        friction_nm_s_per_rad: f64,
        start_rad: f64,
        step_s: f64,
    ) -> Result<Self, crate::physics::PhysicsError> {
        // Effort and speed limits are the controller's business; the URDF values are nominal.
        let urdf = rig_urdf_with_rotor(load, rotor_inertia_kg_m2, 1.0e3, 1.0e3);
        let config = crate::physics::WorldConfig {
            step_s,
            ..crate::physics::WorldConfig::default()
        };
        let mut world = crate::physics::RapierWorld::from_urdf_str(&urdf, config)?;
        world.set_joint_positions(&[start_rad])?;
        Ok(Self {
            world,
            inertia_kg_m2: (rotor_inertia_kg_m2 + load.inertia_kg_m2()).max(1e-6),
            friction_nm_s_per_rad: friction_nm_s_per_rad.max(0.0),
            external_nm: 0.0,
        })
    }
}

impl Plant for WorldPlant {
    fn step(&mut self, torque_nm: f64, dt_s: f64) {
        let step = self.world.config().step_s;
        let steps = (dt_s / step).round().max(1.0) as u32;
        for _ in 0..steps {
            let friction = -self.friction_nm_s_per_rad * self.velocity_rad_s();
            self.world.step(&[torque_nm + friction + self.external_nm]);
        }
    }

    fn position_rad(&self) -> f64 {
        self.world.joint_positions().first().copied().unwrap_or(0.0)
    }

    fn velocity_rad_s(&self) -> f64 {
        self.world
            .joint_velocities()
            .first()
            .copied()
            .unwrap_or(0.0)
    }

    fn inertia_kg_m2(&self) -> f64 {
        self.inertia_kg_m2
    }

    fn set_external_torque_nm(&mut self, torque_nm: f64) {
        self.external_nm = finite_or_zero(torque_nm);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pendulum_swings_with_the_small_angle_period() {
        let (m, l) = (1.0, 0.5);
        let mut plant = RigPlant::new(
            Load::Pendulum {
                mass_kg: m,
                length_m: l,
            },
            0.0,
            0.0,
            0.05,
        );
        // Count zero crossings over 10 s; small-angle period 2π√(l/g).
        let dt = 1e-4;
        let mut crossings = 0;
        let mut last = plant.position_rad();
        for _ in 0..100_000 {
            plant.step(0.0, dt);
            if last > 0.0 && plant.position_rad() <= 0.0 {
                crossings += 1;
            }
            last = plant.position_rad();
        }
        let expected = 10.0 / (2.0 * std::f64::consts::PI * (l / GRAVITY_M_S2).sqrt());
        assert!(
            (f64::from(crossings) - expected).abs() <= 1.0,
            "{crossings} vs {expected}"
        );
    }

    #[test]
    fn gravity_torque_peaks_horizontal() {
        let load = Load::Pendulum {
            mass_kg: 2.0,
            length_m: 0.3,
        };
        let horizontal = load.gravity_torque_nm(std::f64::consts::FRAC_PI_2).abs();
        assert!((horizontal - 2.0 * GRAVITY_M_S2 * 0.3).abs() < 1e-9);
        assert!(rig_urdf(load, 60.0, 20.0).contains("<joint name=\"motor\""));
    }
}
