//! Joint friction, rotor inertia (armature) and masses of the Piper model.
//!
//! - A disabled arm sinks and comes to rest within 3 s instead of swinging.
//! - The vendor demo's MIT gains (kp 10, kd 0.8) hold the zero pose without chatter: the
//!   armature makes the wrist heavy enough for an explicit 1 kHz damping term.
//! - The armature enters rapier's dynamics exactly as `ArmModel::mass_matrix` says.
//! - Masses: link6 no longer counts the gripper twice; J3 holds the audit pose with < 5 N·m.

use bus::CanFrame;
use sim::physics::{RapierWorld, WorldConfig};
use sim::piper::codec::mit::{pack, MitCommand, MitRaw};
use sim::piper::kinematics::PIPER_URDF;
use sim::piper::motor::ARMATURE_KG_M2;
use sim::piper::{Firmware, FirmwareProfile, PiperConfig};

fn frame(id: u16, data: [u8; 8]) -> CanFrame {
    CanFrame::standard(id, &data).expect("valid frame")
}

fn boot(q0_deg: [f64; 6]) -> Firmware {
    Firmware::new(PiperConfig {
        firmware: FirmwareProfile::V1_8_2,
        initial_joints_rad: q0_deg.map(f64::to_radians),
        ..PiperConfig::default()
    })
    .expect("firmware boots")
}

/// The pose of the mass audit (issue: J3 needed 6.2 N·m there with link6 counted twice).
const AUDIT_POSE_DEG: [f64; 6] = [20.0, 30.0, -40.0, 10.0, 20.0, 30.0];

#[test]
fn disabled_arm_sinks_and_comes_to_rest_within_3_s() {
    let mut fw = boot(AUDIT_POSE_DEG);
    let start = fw.snapshot().joint_positions_rad;
    let mut last_moving_ms = 0usize;
    let mut peak_speed: f64 = 0.0;
    for ms in 1..=5000 {
        fw.tick();
        fw.take_output();
        let v = fw.snapshot().joint_velocities_rad_s;
        let fastest = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        peak_speed = peak_speed.max(fastest);
        // 0.1 °/s: well below what a person would see moving.
        if fastest > 0.1f64.to_radians() {
            last_moving_ms = ms;
        }
    }
    let snap = fw.snapshot();
    eprintln!(
        "disabled arm: peak {:.1} °/s, at rest after {} ms; moved by {:?} °",
        peak_speed.to_degrees(),
        last_moving_ms,
        std::array::from_fn::<f64, 6, _>(|j| (snap.joint_positions_rad[j] - start[j]).to_degrees())
    );
    assert!(snap.joint_torques_nm.iter().all(|&t| t == 0.0));
    assert!(
        peak_speed > 0.1,
        "the unpowered arm should sink under gravity, peak {peak_speed} rad/s"
    );
    assert!(
        last_moving_ms <= 3000,
        "still moving {last_moving_ms} ms after power-on"
    );
    // J1 (vertical axis) is not loaded by gravity: the links swinging must not spin it.
    let j1_moved_deg = (snap.joint_positions_rad[0] - start[0]).to_degrees().abs();
    assert!(j1_moved_deg < 5.0, "J1 turned {j1_moved_deg}°");
}

/// MIT command on every joint: hold `p` with `kp`, `kd`.
fn mit_hold(fw: &mut Firmware, kp: f64, kd: f64) {
    let packing = FirmwareProfile::V1_8_2.mit_packing();
    for j in 0..6u16 {
        let cmd = MitCommand {
            p_des_rad: 0.0,
            v_des_rad_s: 0.0,
            kp,
            kd,
            t_ff_nm: 0.0,
        };
        let raw = MitRaw::from_command(&cmd, packing);
        fw.handle_frame(&frame(0x15A + j, pack(raw, packing)));
    }
}

#[test]
fn vendor_mit_gains_hold_the_zero_pose_without_chatter() {
    // J5 at 0 aligns J4 and J6: they drive only link4 + link5 (+ link6 and the gripper for
    // J6). Start them 10° off so the law has to move them to the zero pose.
    let mut fw = boot([0.0, 0.0, 0.0, 10.0, 0.0, -10.0]);
    fw.handle_frame(&frame(0x471, [7, 2, 0, 0, 0, 0, 0, 0]));
    fw.handle_frame(&frame(
        0x151,
        [
            1,
            FirmwareProfile::V1_8_2.mit_mode_code(),
            0,
            0xAD,
            0,
            0,
            0,
            0,
        ],
    ));
    let mut peak_wrist_speed: f64 = 0.0;
    let mut saturated_steps = 0usize;
    for _ in 0..3000 {
        // The host streams at 200 Hz; the firmware keeps the last command between frames.
        mit_hold(&mut fw, 10.0, 0.8);
        for _ in 0..5 {
            fw.tick();
        }
        fw.take_output();
        let snap = fw.snapshot();
        for j in [3, 5] {
            peak_wrist_speed = peak_wrist_speed.max(snap.joint_velocities_rad_s[j].abs());
            if snap.joint_torques_nm[j].abs() > 7.9 {
                saturated_steps += 1;
            }
        }
        if peak_wrist_speed > 10.0 {
            break;
        }
    }
    let snap = fw.snapshot();
    eprintln!(
        "MIT kp 10 kd 0.8 at the zero pose: peak J4/J6 speed {:.4} rad/s, saturated samples \
         {saturated_steps}, J4 {:.4}°, J6 {:.4}°",
        peak_wrist_speed,
        snap.joint_positions_rad[3].to_degrees(),
        snap.joint_positions_rad[5].to_degrees()
    );
    // A well-behaved step: 0.17 rad at ω = √(kp/I) ≈ 10 rad/s peaks below 1.7 rad/s. Without
    // the armature J4/J6 run away to > 20 rad/s against the 8 N·m limit.
    assert!(
        peak_wrist_speed < 2.0,
        "J4/J6 ran up to {peak_wrist_speed} rad/s"
    );
    assert_eq!(saturated_steps, 0, "J4/J6 torque hit the 8 N·m limit");
    // Settled within the kinetic-friction dead band (0.1 N·m / kp 10 = 0.01 rad) plus margin.
    for j in [3, 5] {
        assert!(
            snap.joint_positions_rad[j].abs() < 0.05,
            "J{} drifted to {} rad",
            j + 1,
            snap.joint_positions_rad[j]
        );
    }
}

/// The Piper URDF without dry friction, so a small torque pulse is not swallowed by it.
fn frictionless_urdf() -> String {
    let mut out = String::with_capacity(PIPER_URDF.len());
    let mut rest = PIPER_URDF;
    while let Some(i) = rest.find("friction=\"") {
        let value_start = i + "friction=\"".len();
        out.push_str(&rest[..value_start]);
        out.push('0');
        let Some(end) = rest[value_start..].find('"') else {
            break;
        };
        rest = &rest[value_start + end..];
    }
    out.push_str(rest);
    out
}

#[test]
fn armature_enters_rapier_as_the_model_mass_matrix_says() {
    let mut world = RapierWorld::from_urdf_str(&frictionless_urdf(), WorldConfig::default())
        .expect("the Piper URDF loads");
    let q = [0.3, 1.0, -1.2, 0.4, -0.5, 0.2, 0.0, 0.0];
    for (j, a) in ARMATURE_KG_M2.iter().enumerate() {
        world.set_armature(j, *a);
    }
    world.set_joint_positions(&q).expect("pose within limits");
    let mass = world.model().mass_matrix(&q).expect("valid pose");
    for j in 0..6 {
        assert!(
            mass[(j, j)] > ARMATURE_KG_M2[j],
            "armature missing on J{}",
            j + 1
        );
    }
    // One step from rest with gravity held and a pulse on J4: Δv = dt·M⁻¹·τ.
    let mut tau = world.gravity_torques(&q).expect("valid pose");
    let pulse_nm = 1.0;
    tau[3] += pulse_nm;
    world.step(&tau);
    let dv = world.joint_velocities();
    let inverse = mass
        .view((0, 0), (6, 6))
        .into_owned()
        .try_inverse()
        .expect("mass matrix invertible");
    let expected = inverse.column(3) * (pulse_nm * world.config().step_s);
    for j in 0..6 {
        let tolerance = 0.03 * expected[3].abs();
        assert!(
            (dv[j] - expected[j]).abs() < tolerance,
            "J{}: Δv {} vs M⁻¹τ·dt {}",
            j + 1,
            dv[j],
            expected[j]
        );
    }
    eprintln!(
        "J4 pulse: Δv {:.6} rad/s vs {:.6}; J4 inertia with armature {:.4} kg·m²",
        dv[3],
        expected[3],
        mass[(3, 3)]
    );
}

#[test]
fn masses_match_agilex_and_j3_holds_the_audit_pose_under_5_nm() {
    let world = RapierWorld::from_urdf_str(PIPER_URDF, WorldConfig::default()).expect("loads");
    let model = world.model();
    let base = model.inertials()[model.link_index("base_link").expect("base")].mass_kg;
    let moving = model.moving_mass_kg();
    eprintln!(
        "moving mass {moving:.3} kg, with base {:.3} kg",
        moving + base
    );
    // AgileX's current URDF with the gripper: ≈ 4.66 kg including the 1.02 kg base.
    assert!((moving + base - 4.66).abs() < 0.05, "{}", moving + base);
    let mut q = vec![0.0; 8];
    for (j, deg) in AUDIT_POSE_DEG.iter().enumerate() {
        q[j] = deg.to_radians();
    }
    let tau = world.gravity_torques(&q).expect("valid pose");
    eprintln!("gravity torques at the audit pose: {tau:?}");
    assert!(tau[2].abs() < 5.0, "J3 needs {} N·m", tau[2]);
    assert!(tau[2].abs() > 3.0, "J3 needs only {} N·m", tau[2]);

    // The old link6 entry (0.46 kg at 46 mm, the gripper a second time) is what pushed J3 up.
    let link6 = "<mass value=\"0.007\"/>";
    assert!(PIPER_URDF.contains(link6));
    let doubled = PIPER_URDF.replace(link6, "<mass value=\"0.46\"/>");
    let old = RapierWorld::from_urdf_str(&doubled, WorldConfig::default()).expect("loads");
    let old_tau = old.gravity_torques(&q).expect("valid pose");
    eprintln!(
        "J3 at the audit pose: {:.3} N·m now, {:.3} N·m with link6 = 0.46 kg",
        tau[2], old_tau[2]
    );
    assert!(old_tau[2].abs() > tau[2].abs() + 1.0);
}
