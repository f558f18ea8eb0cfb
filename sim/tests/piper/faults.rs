//! Injected faults as they show on the wire (virtual bus, paused clock).

use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualNode};
use bus::{CanBus, CanFrame};
use sim::physics::ObstacleShape;
use sim::piper::{FirmwareProfile, NtcBoard, PiperConfig, PiperFault, PiperHandle};
use testkit::emulators::piper::{collect, last, spawn_emulator};

fn f8(id: u16, data: [u8; 8]) -> CanFrame {
    CanFrame::standard(id, &data).unwrap()
}

fn start() -> (VirtualBus, VirtualNode, PiperHandle) {
    spawn_emulator(PiperConfig {
        firmware: FirmwareProfile::V1_8_2,
        initial_joints_rad: [0.0, 0.5, -0.5, 0.0, 0.0, 0.0],
        ..PiperConfig::default()
    })
}

async fn enable(host: &VirtualNode) {
    host.send(f8(0x471, [7, 2, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    host.send(f8(0x151, [1, 1, 50, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
}

#[tokio::test(start_paused = true)]
async fn joint_comm_loss_silences_that_joint() {
    let (_bus, host, emu) = start();
    enable(&host).await;
    collect(&host, Duration::from_millis(50)).await;
    emu.inject(PiperFault::CommLoss { joint: 3 }).unwrap();
    // Frames already queued on the bus before the fault still arrive.
    collect(&host, Duration::from_millis(10)).await;
    let frames = collect(&host, Duration::from_millis(100)).await;
    let status = last(&frames, 0x2A1).unwrap();
    assert_eq!((status[1], status[7]), (0x05, 0b100));
    assert!(last(&frames, 0x253).is_none() && last(&frames, 0x263).is_none());
    assert!(last(&frames, 0x252).is_some() && last(&frames, 0x264).is_some());
    emu.clear(PiperFault::CommLoss { joint: 3 }).unwrap();
    let frames = collect(&host, Duration::from_millis(100)).await;
    let status = last(&frames, 0x2A1).unwrap();
    assert_eq!((status[1], status[7]), (0x00, 0));
    assert!(last(&frames, 0x253).is_some() && last(&frames, 0x263).is_some());
    // The joint's driver went down with the link: it needs a new enable.
    assert_eq!(last(&frames, 0x263).unwrap()[5] & 0x40, 0);
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn latched_driver_faults_clear_with_0x475() {
    let (_bus, host, emu) = start();
    enable(&host).await;
    collect(&host, Duration::from_millis(50)).await;
    for (fault, bit) in [
        (PiperFault::OverCurrent { joint: 2 }, 0x04u8),
        (PiperFault::DriverError { joint: 2 }, 0x20),
        (PiperFault::Stall { joint: 2 }, 0x80),
    ] {
        emu.inject(fault).unwrap();
        let frames = collect(&host, Duration::from_millis(60)).await;
        assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x09, "{fault:?}");
        let st = last(&frames, 0x262).unwrap()[5];
        assert_eq!(st & bit, bit, "{fault:?}: {st:#x}");
        assert_eq!(st & 0x40, 0, "{fault:?}: driver must disable");
        host.send(f8(0x475, [2, 0, 0, 0x7F, 0xFF, 0xAE, 0, 0]))
            .await
            .unwrap();
        let frames = collect(&host, Duration::from_millis(60)).await;
        assert_eq!(
            last(&frames, 0x262).unwrap()[5] & bit,
            0,
            "{fault:?} not cleared"
        );
        assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x00);
    }
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn temperatures_under_voltage_and_board_ntc() {
    let (_bus, host, emu) = start();
    emu.inject(PiperFault::MotorOverTemp {
        joint: 4,
        temp_c: 95.0,
    })
    .unwrap();
    emu.inject(PiperFault::DriverOverTemp {
        joint: 5,
        temp_c: 85.0,
    })
    .unwrap();
    let frames = collect(&host, Duration::from_millis(60)).await;
    let j4 = last(&frames, 0x264).unwrap();
    assert_eq!((j4[4], j4[5] & 0x02), (95, 0x02));
    let j5 = last(&frames, 0x265).unwrap();
    assert_eq!(
        (i16::from_be_bytes([j5[2], j5[3]]), j5[5] & 0x08),
        (85, 0x08)
    );
    assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x09);
    emu.clear(PiperFault::MotorOverTemp {
        joint: 4,
        temp_c: 0.0,
    })
    .unwrap();
    emu.clear(PiperFault::DriverOverTemp {
        joint: 5,
        temp_c: 0.0,
    })
    .unwrap();
    emu.inject(PiperFault::UnderVoltage { voltage_v: 18.0 })
        .unwrap();
    let frames = collect(&host, Duration::from_millis(60)).await;
    for id in 0x261..=0x266 {
        let d = last(&frames, id).unwrap();
        assert_eq!(
            (u16::from_be_bytes([d[0], d[1]]), d[5] & 0x01),
            (180, 0x01),
            "{id:#x}"
        );
    }
    assert_eq!(
        last(&frames, 0x2A8).unwrap()[6] & 0x01,
        0x01,
        "gripper under-voltage bit"
    );
    emu.clear(PiperFault::UnderVoltage { voltage_v: 0.0 })
        .unwrap();
    emu.inject(PiperFault::NtcOverTemp {
        board: NtcBoard::Main,
    })
    .unwrap();
    let frames = collect(&host, Duration::from_millis(30)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x0E);
    emu.clear(PiperFault::NtcOverTemp {
        board: NtcBoard::Main,
    })
    .unwrap();
    emu.inject(PiperFault::NtcOverTemp {
        board: NtcBoard::BrakeResistor,
    })
    .unwrap();
    let frames = collect(&host, Duration::from_millis(30)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x0F);
    emu.clear(PiperFault::NtcOverTemp {
        board: NtcBoard::BrakeResistor,
    })
    .unwrap();
    let frames = collect(&host, Duration::from_millis(30)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x00);
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn external_torque_beyond_the_level_threshold_is_a_collision() {
    let (_bus, host, emu) = start();
    host.send(f8(0x47A, [4, 4, 4, 4, 4, 4, 0, 0]))
        .await
        .unwrap();
    enable(&host).await;
    collect(&host, Duration::from_millis(100)).await;
    // Level 4 on J1 (32 N·m motor): threshold 32·5/12 ≈ 13.3 N·m. 5 N·m is tolerated …
    emu.inject(PiperFault::ExternalTorque {
        joint: 1,
        torque_nm: 5.0,
    })
    .unwrap();
    let frames = collect(&host, Duration::from_millis(300)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x00);
    // … 20 N·m is not.
    emu.inject(PiperFault::ExternalTorque {
        joint: 1,
        torque_nm: 20.0,
    })
    .unwrap();
    let frames = collect(&host, Duration::from_millis(300)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x07);
    assert_eq!(
        last(&frames, 0x261).unwrap()[5] & 0x10,
        0x10,
        "collision bit"
    );
    emu.clear(PiperFault::ExternalTorque {
        joint: 1,
        torque_nm: 0.0,
    })
    .unwrap();
    host.send(f8(0x150, [2, 0, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let frames = collect(&host, Duration::from_millis(50)).await;
    assert_eq!(
        last(&frames, 0x2A1).unwrap()[1],
        0x00,
        "reset clears the collision"
    );
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn obstacle_contact_stops_the_arm() {
    let (_bus, host, emu) = start();
    host.send(f8(0x47A, [6, 6, 6, 6, 6, 6, 0, 0]))
        .await
        .unwrap();
    enable(&host).await;
    collect(&host, Duration::from_millis(100)).await;
    // A wall in the path of the forearm as J1 swings +90°.
    let id = emu.add_obstacle(
        ObstacleShape::Box {
            half_extents_m: [0.3, 0.02, 0.3],
        },
        [0.0, 0.25, 0.2],
    );
    let target = 90_000i32.to_be_bytes();
    let j2 = 28_648i32.to_be_bytes();
    host.send(f8(
        0x155,
        [
            target[0], target[1], target[2], target[3], j2[0], j2[1], j2[2], j2[3],
        ],
    ))
    .await
    .unwrap();
    let j3 = (-28_648i32).to_be_bytes();
    host.send(f8(0x156, [j3[0], j3[1], j3[2], j3[3], 0, 0, 0, 0]))
        .await
        .unwrap();
    host.send(f8(0x157, [0; 8])).await.unwrap();
    let frames = collect(&host, Duration::from_secs(3)).await;
    let snap = emu.snapshot();
    assert!(
        snap.joint_positions_rad[0].to_degrees() < 85.0,
        "passed through the wall: {:?}",
        snap.joint_positions_rad
    );
    assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x07, "collision status");
    emu.remove_obstacle(id);
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn estop_and_teach_button_and_gripper_sensor() {
    let (_bus, host, emu) = start();
    emu.inject(PiperFault::TeachButton).unwrap();
    let frames = collect(&host, Duration::from_millis(30)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[0], 0x02, "teach mode");
    emu.clear(PiperFault::TeachButton).unwrap();
    let frames = collect(&host, Duration::from_millis(30)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[0], 0x00);
    emu.inject(PiperFault::Estop).unwrap();
    let frames = collect(&host, Duration::from_millis(30)).await;
    assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x01);
    host.send(f8(0x150, [2, 0, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let frames = collect(&host, Duration::from_millis(30)).await;
    assert_eq!(
        last(&frames, 0x2A1).unwrap()[1],
        0x00,
        "reset releases the e-stop"
    );
    emu.inject(PiperFault::GripperSensorFault).unwrap();
    let frames = collect(&host, Duration::from_millis(30)).await;
    assert_eq!(last(&frames, 0x2A8).unwrap()[6] & 0x10, 0x10);
    assert!(emu.inject(PiperFault::Stall { joint: 7 }).is_err());
    assert!(emu
        .inject(PiperFault::MotorOverTemp {
            joint: 1,
            temp_c: f64::NAN
        })
        .is_err());
    emu.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn blocked_motor_trips_the_stall_protection() {
    let (_bus, host, emu) = start();
    // Collision protection off (level 0, the factory default): the motor pushes until stall.
    enable(&host).await;
    collect(&host, Duration::from_millis(100)).await;
    emu.add_obstacle(
        ObstacleShape::Box {
            half_extents_m: [0.3, 0.02, 0.3],
        },
        [0.0, 0.25, 0.2],
    );
    let target = 90_000i32.to_be_bytes();
    let j2 = 28_648i32.to_be_bytes();
    host.send(f8(
        0x155,
        [
            target[0], target[1], target[2], target[3], j2[0], j2[1], j2[2], j2[3],
        ],
    ))
    .await
    .unwrap();
    let j3 = (-28_648i32).to_be_bytes();
    host.send(f8(0x156, [j3[0], j3[1], j3[2], j3[3], 0, 0, 0, 0]))
        .await
        .unwrap();
    host.send(f8(0x157, [0; 8])).await.unwrap();
    let frames = collect(&host, Duration::from_secs(5)).await;
    // Whichever joint the wall blocks ends up pinned at its torque limit.
    let stalled: Vec<u32> = (0x261..=0x266)
        .filter(|&id| last(&frames, id).unwrap()[5] & 0x80 != 0)
        .collect();
    let snap = emu.snapshot();
    assert!(
        !stalled.is_empty(),
        "no stall bit; q {:?} tau {:?}",
        snap.joint_positions_rad,
        snap.joint_torques_nm
    );
    for id in &stalled {
        assert_eq!(
            last(&frames, *id).unwrap()[5] & 0x40,
            0,
            "{id:#x} still enabled"
        );
    }
    assert_eq!(last(&frames, 0x2A1).unwrap()[1], 0x09);
    emu.shutdown().await;
}
