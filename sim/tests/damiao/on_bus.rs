//! Motors on the virtual bus through `DamiaoBus::spawn`, under tokio's paused clock: routing
//! by id, the turnaround, the handle's side door, the CAN timeout in virtual time, the flash.

use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig, VirtualNode};
use bus::{CanBus, CanFrame, FdFlags};
use sim::damiao::codec::{register_payload, RegisterCmd, Special};
use sim::damiao::registers::rid;
use sim::damiao::{
    DamiaoBus, DamiaoConfig, DamiaoError, DamiaoHandle, Model, MotorConfig, TURNAROUND,
};
use sim::fault_args::FaultArgs;

fn spawn(bus: &VirtualBus, motors: Vec<MotorConfig>) -> DamiaoHandle {
    let node: Arc<dyn CanBus> = Arc::new(bus.attach("emulator"));
    DamiaoBus::spawn(DamiaoConfig::new(motors), node).expect("spawn")
}

/// Every frame the host receives within `window`, with when it arrived.
async fn collect(host: &VirtualNode, window: Duration) -> Vec<(tokio::time::Instant, CanFrame)> {
    let mut out = Vec::new();
    let end = tokio::time::Instant::now() + window;
    while let Ok(Ok(received)) = tokio::time::timeout_at(end, host.recv()).await {
        out.push((tokio::time::Instant::now(), received.frame));
    }
    out
}

fn special(esc: u16, command: Special) -> CanFrame {
    CanFrame::standard(esc, &command.payload()).unwrap()
}

fn register(esc: u16, cmd: RegisterCmd, rid: u8, value: [u8; 4]) -> CanFrame {
    CanFrame::standard(0x7FF, &register_payload(esc, cmd.byte(), rid, value)).unwrap()
}

/// The state nibble of the one feedback frame on `mst` among `frames`.
fn state_on(frames: &[(tokio::time::Instant, CanFrame)], mst: u32) -> u8 {
    let on: Vec<&CanFrame> = frames
        .iter()
        .map(|(_, f)| f)
        .filter(|f| f.raw_id() == mst)
        .collect();
    assert_eq!(on.len(), 1, "expected one frame on 0x{mst:03X}: {frames:?}");
    on[0].data()[0] >> 4
}

#[tokio::test(start_paused = true)]
async fn motors_answer_on_their_own_ids_after_the_turnaround() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emulator = spawn(
        &bus,
        vec![
            MotorConfig::new(0x01, Model::DM8009),
            MotorConfig::new(0x02, Model::DM4310),
        ],
    );
    assert_eq!(emulator.power_on_ids(), [1, 2]);
    let host = bus.attach("host");
    let sent = tokio::time::Instant::now();
    host.send(special(0x02, Special::Enable)).await.unwrap();
    host.send(special(0x01, Special::Enable)).await.unwrap();
    let replies = collect(&host, Duration::from_millis(10)).await;
    assert_eq!(replies.len(), 2, "{replies:?}");
    for (at, frame) in &replies {
        let esc = frame.raw_id() - 0x10;
        assert!(esc == 1 || esc == 2, "{frame}");
        assert_eq!(
            frame.data()[0],
            0x10 | esc as u8,
            "state 1, id nibble: {frame}"
        );
        assert!(
            at.duration_since(sent) >= TURNAROUND,
            "{frame} came too early"
        );
    }
    let snapshot = emulator.snapshot().await.unwrap();
    assert!(snapshot.iter().all(|m| m.enabled && m.kind == "damiao"));
    assert_eq!(snapshot[0].model, "DM8009");
    // Nobody answers ESC_ID 3.
    host.send(special(0x03, Special::Enable)).await.unwrap();
    assert!(collect(&host, Duration::from_millis(10)).await.is_empty());
    emulator.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn the_handle_injects_clears_and_refuses_what_it_cannot_do() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emulator = spawn(
        &bus,
        vec![
            MotorConfig::new(0x01, Model::DM4340),
            MotorConfig::new(0x02, Model::DM4310),
        ],
    );
    let host = bus.attach("host");
    for esc in [1, 2] {
        host.send(special(esc, Special::Enable)).await.unwrap();
    }
    collect(&host, Duration::from_millis(5)).await;
    emulator
        .inject(2, "over_voltage", &FaultArgs::new())
        .await
        .unwrap();
    for esc in [1, 2] {
        host.send(register(esc, RegisterCmd::Refresh, 0, [0; 4]))
            .await
            .unwrap();
    }
    let replies = collect(&host, Duration::from_millis(5)).await;
    assert_eq!(state_on(&replies, 0x11), 1);
    assert_eq!(state_on(&replies, 0x12), 8);
    let snapshot = emulator.snapshot().await.unwrap();
    assert_eq!(snapshot[1].faults, ["over_voltage"]);
    // Cause removed, then the host's FB: clear.
    emulator
        .clear(2, "over_voltage", &FaultArgs::new())
        .await
        .unwrap();
    host.send(special(2, Special::ClearError)).await.unwrap();
    let replies = collect(&host, Duration::from_millis(5)).await;
    assert_eq!(state_on(&replies, 0x12), 0);
    // Refusals.
    assert!(matches!(
        emulator.inject(3, "overload", &FaultArgs::new()).await,
        Err(DamiaoError::UnknownMotor { esc_id: 3 })
    ));
    assert!(matches!(
        emulator.inject(1, "melted", &FaultArgs::new()).await,
        Err(DamiaoError::Fault { esc_id: 1, .. })
    ));
    let hot = emulator.set_temperature(1, 1e308).await.unwrap_err();
    assert_eq!(
        hot.to_string(),
        "motor 0x001: `temperature_c` must be between -40 and 200, got 1e308"
    );
    assert!(
        emulator.set_external_torque(1, 271.0).await.is_err(),
        "10 × 27 N·m"
    );
    emulator.set_external_torque(1, 5.0).await.unwrap();
    emulator.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn the_can_timeout_fires_in_virtual_time_and_save_keeps_the_flash() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emulator = spawn(&bus, vec![MotorConfig::new(0x04, Model::DM4340)]);
    let host = bus.attach("host");
    // TIMEOUT 1000 × 50 µs = 50 ms.
    host.send(register(
        4,
        RegisterCmd::Write,
        rid::TIMEOUT,
        1000u32.to_le_bytes(),
    ))
    .await
    .unwrap();
    host.send(special(4, Special::Enable)).await.unwrap();
    let replies = collect(&host, Duration::from_millis(5)).await;
    assert_eq!(
        replies[0].1.data(),
        [0x04, 0x00, 0x55, 0x09, 0xE8, 0x03, 0, 0]
    );
    assert_eq!(state_on(&replies[1..], 0x14), 1);
    // Kept alive by frames every 20 ms …
    for _ in 0..5 {
        tokio::time::sleep(Duration::from_millis(20)).await;
        host.send(register(4, RegisterCmd::Refresh, 0, [0; 4]))
            .await
            .unwrap();
    }
    assert!(emulator.snapshot().await.unwrap()[0].enabled);
    // … and latched after 50 ms of silence.
    tokio::time::sleep(Duration::from_millis(80)).await;
    let snapshot = emulator.snapshot().await.unwrap();
    assert!(!snapshot[0].enabled);
    assert_eq!(snapshot[0].faults, ["comm_lost"]);
    collect(&host, Duration::from_millis(1)).await;
    // Save (disabled by the latch): the flash image holds the timeout.
    host.send(register(4, RegisterCmd::Save, 1, [0; 4]))
        .await
        .unwrap();
    assert!(
        collect(&host, Duration::from_millis(5)).await.is_empty(),
        "no reply to save"
    );
    let flash = emulator.flash().await.unwrap();
    assert_eq!(flash[0]["registers"]["TIMEOUT"], 1000.0);
    emulator.shutdown().await;
    // Powered on again from it.
    let again = MotorConfig::from_persisted(Model::DM4340, &flash[0]).unwrap();
    let emulator = spawn(&bus, vec![again]);
    assert_eq!(emulator.power_on_ids(), [4]);
    emulator.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn configurations_the_firmware_would_refuse_do_not_start() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let node = || -> Arc<dyn CanBus> { Arc::new(bus.attach("emulator")) };
    let twice = DamiaoConfig::new(vec![
        MotorConfig::new(0x01, Model::DM4310),
        MotorConfig::new(0x01, Model::DM4340),
    ]);
    assert!(matches!(
        DamiaoBus::spawn(twice, node()),
        Err(DamiaoError::DuplicateEscId { esc_id: 1 })
    ));
    let wide = DamiaoConfig::new(vec![MotorConfig::new(0x800, Model::DM4310)]);
    let error = DamiaoBus::spawn(wide, node()).unwrap_err();
    assert!(error.to_string().contains("esc_id"), "{error}");
}

/// The OpenArm runs its Damiao buses as CAN FD: a motor addressed in CAN FD answers in CAN FD
/// with the request's flags (BRS as sent), one addressed in classic CAN in classic CAN.
#[tokio::test(start_paused = true)]
async fn a_motor_answers_in_the_format_it_was_addressed_in() {
    let bus = VirtualBus::new(VirtualBusConfig {
        data_bitrate_bps: Some(5_000_000),
        ..VirtualBusConfig::default()
    });
    let emulator = spawn(&bus, vec![MotorConfig::new(0x01, Model::DM4310)]);
    let host = bus.attach("host");
    let fd = |frame: CanFrame, flags: FdFlags| CanFrame::fd(frame.id(), frame.data(), flags);
    let switched = FdFlags {
        brs: true,
        esi: false,
    };
    host.send(fd(special(0x01, Special::Enable), switched).unwrap())
        .await
        .unwrap();
    let replies = collect(&host, Duration::from_millis(5)).await;
    assert_eq!(replies.len(), 1, "{replies:?}");
    let (_, reply) = replies[0];
    assert_eq!(reply.raw_id(), 0x11, "{reply}");
    assert_eq!(reply.fd_flags(), Some(switched), "{reply}");
    assert_eq!(reply.data()[0] >> 4, 1, "enabled: {reply}");

    let refresh = register(0x01, RegisterCmd::Refresh, 0, [0; 4]);
    host.send(fd(refresh, FdFlags::default()).unwrap())
        .await
        .unwrap();
    let replies = collect(&host, Duration::from_millis(5)).await;
    assert_eq!(replies.len(), 1, "{replies:?}");
    assert_eq!(replies[0].1.fd_flags(), Some(FdFlags::default()));

    host.send(refresh).await.unwrap();
    let replies = collect(&host, Duration::from_millis(5)).await;
    assert_eq!(replies.len(), 1, "{replies:?}");
    assert!(!replies[0].1.is_fd(), "classic request: {}", replies[0].1);
    emulator.shutdown().await;
}
