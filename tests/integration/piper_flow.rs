//! The Piper driver against the Piper emulator on the virtual bus, in virtual time.

use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig};
use bus::CanBus;
use driver::piper::{
    FirmwareVersion, GripperCommand, LimitPolicy, MitCommand, MotorSelect, MoveKind, Piper,
    PiperBuilder, PiperError, Timeouts,
};
use sim::piper::flash::Flash;
use sim::piper::{FirmwareProfile, PiperConfig, PiperEmulator, PiperHandle};
use tokio::time::Instant;

/// Flash values that differ from the defaults, so the queries prove they read the emulator.
fn configured_flash() -> Flash {
    Flash {
        max_angle_ddeg: [1400, 1700, 0, 880, 700, 1200],
        min_angle_ddeg: [-1400, 0, -1600, -880, -700, -1200],
        max_speed_crad_s: [250, 260, 270, 280, 290, 300],
        max_acc_crad_s2: [400, 410, 420, 430, 440, 450],
        end_vel_acc: [800, 900, 1100, 1200],
        collision_levels: [1, 2, 3, 4, 5, 6],
        gripper_max_stroke_mm: 100,
        pendant_travel_pct: 150,
        pendant_friction: 3,
        ..Flash::default()
    }
}

fn start(profile: FirmwareProfile) -> (VirtualBus, PiperHandle, Arc<dyn CanBus>) {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let config = PiperConfig {
        firmware: profile,
        flash: Some(configured_flash()),
        ..PiperConfig::default()
    };
    let emulator =
        PiperEmulator::spawn(Arc::new(bus.attach("piper")), config).expect("emulator starts");
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    (bus, emulator, host)
}

fn version_of(profile: FirmwareProfile) -> FirmwareVersion {
    FirmwareVersion::parse(profile.version_string()).expect("profile version parses")
}

async fn full_flow(profile: FirmwareProfile) {
    let (_bus, emulator, host) = start(profile);
    let piper = PiperBuilder::new(host)
        .joint_limits(LimitPolicy::Reject)
        .connect()
        .await
        .expect("connect");

    // Firmware detected at connect, and asked again explicitly.
    assert_eq!(piper.firmware_version(), Some(version_of(profile)));
    let info = piper.query_firmware().await.expect("firmware query");
    assert_eq!(info.software, profile.version_string());

    // Enable, confirmed by the 0x26x bits; the emulator agrees.
    piper
        .enable(MotorSelect::All)
        .await
        .expect("enable confirmed");
    assert!(piper.state().arm_enabled());
    assert_eq!(emulator.snapshot().status.enabled, [true; 6]);

    // MOVE J and arrival.
    let target = [0.3, 0.6, -0.5, 0.2, -0.3, 0.4];
    piper.move_joints_rad(target, 100).await.expect("move");
    piper
        .wait_for_move_mode(MoveKind::J, Duration::from_millis(200))
        .await
        .expect("MOVE J echoed");
    let state = piper
        .wait_for_arrival(0.01, Duration::from_secs(20))
        .await
        .expect("arrival");
    let joints = state.joints_rad().expect("joint feedback");
    let truth = emulator.snapshot().reported_joints_rad;
    for i in 0..6 {
        assert!(
            (joints[i] - target[i]).abs() < 0.01,
            "joint {}: {joints:?} vs {target:?}",
            i + 1
        );
        assert!(
            (joints[i] - truth[i]).abs() < 0.005,
            "joint {}: driver {joints:?} vs emulator {truth:?}",
            i + 1
        );
    }

    // The driver's own FK agrees with the flange pose the firmware reports (independent
    // implementations of the same DH table).
    tokio::time::sleep(Duration::from_millis(20)).await;
    let state = piper.state();
    let fk = piper.forward_kinematics().expect("fk")[5];
    let pose = state.end_pose.expect("end pose").value;
    let [x, y, z] = pose.position_m;
    assert!((fk.x_mm - x * 1000.0).abs() < 1.0, "fk {fk:?} vs {pose:?}");
    assert!((fk.y_mm - y * 1000.0).abs() < 1.0, "fk {fk:?} vs {pose:?}");
    assert!((fk.z_mm - z * 1000.0).abs() < 1.0, "fk {fk:?} vs {pose:?}");

    // Gripper: enable and open to 30 mm.
    let command = GripperCommand {
        stroke_m: 0.03,
        effort_nm: 1.0,
        enable: true,
        clear_error: false,
    };
    piper.gripper(command).await.expect("gripper");
    let state = piper
        .wait_for(
            |s| {
                s.gripper_stroke_m()
                    .is_some_and(|m| (m - 0.03).abs() < 0.001)
            },
            Duration::from_secs(10),
            "gripper at 30 mm",
        )
        .await
        .expect("gripper arrives");
    assert!(state.gripper.expect("gripper").value.status.enabled());

    // Queries return what the emulator was configured with.
    let flash = configured_flash();
    let limits = piper.query_all_joint_limits().await.expect("limits");
    // The flash holds wire units (0.1°, 0.01 rad/s, 0.01 rad/s², 0.001 m/s …); the driver
    // answers in SI.
    let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
    let ddeg = |d: i16| (f64::from(d) / 10.0).to_radians();
    for (i, l) in limits.iter().enumerate() {
        assert!(close(l.max_rad, ddeg(flash.max_angle_ddeg[i])), "{l:?}");
        assert!(close(l.min_rad, ddeg(flash.min_angle_ddeg[i])), "{l:?}");
        let speed = f64::from(flash.max_speed_crad_s[i]) / 100.0;
        assert!(close(l.max_speed_rad_s, speed), "{l:?}");
    }
    let acc = piper.query_all_joint_max_acc().await.expect("max acc");
    for (a, crad) in acc.iter().zip(flash.max_acc_crad_s2) {
        assert!(close(*a, f64::from(crad) / 100.0), "{acc:?}");
    }
    let end = piper.query_end_limits().await.expect("end limits");
    let got = [
        end.linear_m_s,
        end.angular_rad_s,
        end.linear_acc_m_s2,
        end.angular_acc_rad_s2,
    ];
    for (g, milli) in got.iter().zip(flash.end_vel_acc) {
        assert!(close(*g, f64::from(milli) / 1000.0), "{end:?}");
    }
    let collision = piper
        .query_collision_levels()
        .await
        .expect("collision levels");
    assert_eq!(collision, flash.collision_levels);
    let gripper = piper
        .query_gripper_teach_params()
        .await
        .expect("gripper/teach");
    assert_eq!(
        (gripper.teach_coefficient_pct, gripper.friction),
        (flash.pendant_travel_pct, flash.pendant_friction)
    );
    assert!(close(
        gripper.max_stroke_m,
        f64::from(flash.gripper_max_stroke_mm) / 1000.0
    ));

    // Acknowledged settings change what the next query reports.
    piper
        .set_collision_levels([8, 7, 6, 5, 4, 3].map(Some))
        .await
        .expect("acked");
    assert_eq!(
        piper.query_collision_levels().await.expect("collision"),
        [8, 7, 6, 5, 4, 3]
    );
    piper.set_joint_max_speed(1, 2.0).await.expect("acked");
    let limits = piper.query_joint_limits(1).await.expect("limits");
    assert!(close(limits.max_speed_rad_s, 2.0), "{limits:?}");
    // Only the speed was sent: the angle limits kept their flash values.
    assert!(
        close(limits.max_rad, ddeg(flash.max_angle_ddeg[0])),
        "{limits:?}"
    );

    // Disable, confirmed.
    piper
        .disable(MotorSelect::All)
        .await
        .expect("disable confirmed");
    assert_eq!(piper.state().enabled_mask().0, 0);
    piper.disconnect().await;
    emulator.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn piper_full_flow_fw_1_8_8() {
    full_flow(FirmwareProfile::V1_8_8).await;
}

#[tokio::test(start_paused = true)]
async fn piper_full_flow_fw_1_6_3() {
    full_flow(FirmwareProfile::V1_6_3).await;
}

#[tokio::test(start_paused = true)]
async fn piper_mit_mode_uses_the_firmware_code_and_packing() {
    let cases = [
        (FirmwareProfile::V1_6_3, false),
        (FirmwareProfile::V1_6_3, true),
        (FirmwareProfile::V1_8_2, false),
        (FirmwareProfile::V1_8_8, false),
    ];
    for (profile, quirks) in cases {
        let (_bus, emulator, host) = start(profile);
        let piper = PiperBuilder::new(host)
            .mit_quirks(quirks)
            .connect()
            .await
            .expect("connect");
        piper.enable(MotorSelect::All).await.expect("enable");
        piper.set_move_mode(MoveKind::Mit, 0).await.expect("mode");
        piper
            .wait_for_move_mode(MoveKind::Mit, Duration::from_millis(200))
            .await
            .expect("MIT echoed");
        // Hold joint 1 at +0.2 rad with a stiff PD; the emulator must decode our packing.
        let command = MitCommand {
            p_rad: 0.2,
            v_rad_s: 0.0,
            kp: 40.0,
            kd: 1.0,
            t_nm: 0.0,
        };
        let deadline = Instant::now() + Duration::from_secs(3);
        while Instant::now() < deadline {
            piper.mit(1, command).await.expect("mit");
            tokio::time::sleep(Duration::from_millis(5)).await;
        }
        let j1 = emulator.snapshot().reported_joints_rad[0];
        let fed_back = piper.state().joints_rad().expect("joints")[0];
        // Old firmware negates MIT p_des on J1 (spec §10) unless the driver compensates.
        let expected = if version_of(profile).mit_sign_flipped() && !quirks {
            -0.2
        } else {
            0.2
        };
        assert!(
            (j1 - expected).abs() < 0.05,
            "{profile:?} quirks {quirks}: J1 at {j1} rad, wanted {expected}"
        );
        assert!(
            (fed_back - j1).abs() < 0.01,
            "{profile:?}: feedback {fed_back} vs {j1}"
        );
        piper.reset().await.expect("reset");
        piper.disconnect().await;
        emulator.shutdown().await;
    }
}

#[tokio::test(start_paused = true)]
async fn piper_query_on_a_silent_bus_times_out() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
    let timeouts = Timeouts {
        first_feedback: None,
        ..Timeouts::default()
    };
    let piper = PiperBuilder::new(host)
        .timeouts(timeouts)
        .connect()
        .await
        .expect("connect");
    for attempt in 0..2 {
        let start = Instant::now();
        let result = if attempt == 0 {
            piper.query_firmware().await.map(|_| ())
        } else {
            piper.query_all_joint_limits().await.map(|_| ())
        };
        let waited = start.elapsed();
        assert!(
            matches!(result, Err(PiperError::Timeout { .. })),
            "{result:?}"
        );
        assert!(
            waited >= timeouts.query && waited <= timeouts.query + Duration::from_millis(5),
            "{waited:?}"
        );
    }
    assert!(!piper.is_ok());
    piper.disconnect().await;
}

#[tokio::test(start_paused = true)]
async fn piper_link_loss_and_bus_off_are_surfaced() {
    let (bus, emulator, host) = start(FirmwareProfile::V1_8_8);
    let piper: Piper = PiperBuilder::new(host).connect().await.expect("connect");
    tokio::time::sleep(Duration::from_millis(100)).await;
    assert!(piper.is_ok() && piper.state().link.ok);

    // The emulator falls silent: `is_ok` flips within 100 ms of virtual time.
    let silence = bus.faults().silence_node("piper");
    let start = Instant::now();
    piper
        .wait_for(|s| !s.link.ok, Duration::from_millis(100), "link loss")
        .await
        .expect("flip");
    assert!(!piper.is_ok());
    assert!(start.elapsed() <= Duration::from_millis(100));
    bus.faults().remove(silence);
    piper
        .wait_for(|s| s.link.ok, Duration::from_millis(100), "link back")
        .await
        .expect("recovers");

    // Bus-off of the host: sends fail with a typed bus error and the link reports it.
    bus.faults().bus_off("host", Duration::from_millis(200));
    let result = piper.emergency_stop().await;
    assert!(
        matches!(
            result,
            Err(PiperError::Bus {
                source: bus::BusError::BusOff
            })
        ),
        "{result:?}"
    );
    assert!(!piper.is_ok());
    assert_eq!(
        piper.state().link.bus_fault,
        Some(driver::piper::BusFault::BusOff)
    );
    // After recovery, feedback clears the fault.
    piper
        .wait_for(
            |s| s.link.ok,
            Duration::from_millis(500),
            "bus-off recovery",
        )
        .await
        .expect("recovers");
    piper.disconnect().await;
    emulator.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn piper_trajectory_transfer_is_acknowledged() {
    let (_bus, emulator, host) = start(FirmwareProfile::V1_8_2);
    let piper = PiperBuilder::new(host).connect().await.expect("connect");
    for index in 0..3 {
        let ack = piper
            .trajectory_transfer_point(index)
            .await
            .expect("point acked");
        assert_eq!(ack.point, index);
    }
    let ack = piper
        .trajectory_transfer_end(2, 0x1234, 0xBEEF)
        .await
        .expect("package acked");
    // A package CRC failure would be `PiperError::Rejected`: Ok means the arm said 0xAE.
    assert_eq!((ack.name_index, ack.crc16), (0x1234, 0xBEEF));
    piper.disconnect().await;
    emulator.shutdown().await;
}
