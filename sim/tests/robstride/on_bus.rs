//! The emulator on the virtual bus (paused clock): routing between motors, the state file, and
//! "after power cycle" switches.

use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig, VirtualNode};
use bus::{CanBus, CanFrame, CanId, FdFlags};
use sim::robstride::{
    Fault, Model, MotorConfig, RobstrideBus, RobstrideConfig, RobstrideError, RobstrideHandle,
    DEFAULT_HOST_ID,
};

fn spawn(bus: &VirtualBus, config: RobstrideConfig) -> RobstrideHandle {
    let node: Arc<dyn CanBus> = Arc::new(bus.attach("emulator"));
    RobstrideBus::spawn(node, config).expect("spawn")
}

fn ext(id: u32, data: [u8; 8]) -> CanFrame {
    CanFrame::extended(id, &data).unwrap()
}

/// Every frame the host receives within `window`.
async fn collect(host: &VirtualNode, window: Duration) -> Vec<CanFrame> {
    let mut out = Vec::new();
    let end = tokio::time::Instant::now() + window;
    while let Ok(Ok(received)) = tokio::time::timeout_at(end, host.recv()).await {
        out.push(received.frame);
    }
    out
}

fn temp_state(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("armhil-robstride-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("state.json");
    let _ = std::fs::remove_file(&path);
    path
}

#[tokio::test(start_paused = true)]
async fn each_motor_answers_only_its_own_frames() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let config = RobstrideConfig::new(vec![
        MotorConfig::new(1, Model::RS03),
        MotorConfig::new(2, Model::RS00),
        MotorConfig::new(3, Model::RS06),
    ]);
    let emulator = spawn(&bus, config);
    let host = bus.attach("host");
    for motor in [2u32, 3, 1] {
        host.send(ext(0x0300_FD00 | motor, [0; 8])).await.unwrap();
    }
    let replies = collect(&host, Duration::from_millis(20)).await;
    let mut from: Vec<u32> = replies.iter().map(|f| (f.raw_id() >> 8) & 0xFF).collect();
    from.sort_unstable();
    assert_eq!(from, [1, 2, 3]);
    assert!(replies
        .iter()
        .all(|f| f.raw_id() >> 24 == 2 && f.raw_id() & 0xFF == u32::from(DEFAULT_HOST_ID)));
    // Nobody answers ID 4.
    host.send(ext(0x0000_FD04, [0; 8])).await.unwrap();
    assert!(collect(&host, Duration::from_millis(20)).await.is_empty());
    let snapshot = emulator.snapshot().await.unwrap();
    assert!(snapshot
        .iter()
        .all(|m| m.mode == sim::robstride::ModeState::Run));
    assert!(matches!(
        emulator.inject(4, Fault::GateDriver).await,
        Err(RobstrideError::UnknownMotor { can_id: 4 })
    ));
    emulator.shutdown().await;
}

#[tokio::test(start_paused = true)]
async fn configuration_errors_are_typed() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let node: Arc<dyn CanBus> = Arc::new(bus.attach("emulator"));
    let twice = RobstrideConfig::new(vec![
        MotorConfig::new(5, Model::RS03),
        MotorConfig::new(5, Model::RS00),
    ]);
    assert!(matches!(
        RobstrideBus::spawn(Arc::clone(&node), twice),
        Err(RobstrideError::DuplicateCanId { can_id: 5 })
    ));
    let zero = RobstrideConfig::new(vec![MotorConfig::new(0, Model::RS03)]);
    assert!(matches!(
        RobstrideBus::spawn(Arc::clone(&node), zero),
        Err(RobstrideError::InvalidCanId { can_id: 0 })
    ));
    let path = temp_state("garbage");
    std::fs::write(&path, "{ not json").unwrap();
    let mut bad_file = RobstrideConfig::new(vec![MotorConfig::new(1, Model::RS03)]);
    bad_file.state_file = Some(path.clone());
    assert!(matches!(
        RobstrideBus::spawn(node, bad_file),
        Err(RobstrideError::StateFile(_))
    ));
    let _ = std::fs::remove_file(path);
}

#[tokio::test(start_paused = true)]
async fn baud_and_protocol_switches_take_effect_after_a_restart() {
    let path = temp_state("switch");
    let mut config = RobstrideConfig::new(vec![
        MotorConfig::new(1, Model::RS03),
        MotorConfig::new(2, Model::RS03),
    ]);
    config.state_file = Some(path.clone());
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emulator = spawn(&bus, config.clone());
    let host = bus.attach("host");
    // Motor 1 → 500 kbit/s, motor 2 → MIT protocol; both still answer until power-off.
    host.send(ext(0x1700_FD01, [1, 2, 3, 4, 5, 6, 2, 0]))
        .await
        .unwrap();
    host.send(ext(0x1900_FD02, [1, 2, 3, 4, 5, 6, 2, 0]))
        .await
        .unwrap();
    let replies = collect(&host, Duration::from_millis(20)).await;
    assert_eq!(replies.len(), 2);
    assert!(replies.iter().all(|f| f.raw_id() >> 24 == 0));
    host.send(ext(0x0000_FD01, [0; 8])).await.unwrap();
    assert_eq!(collect(&host, Duration::from_millis(20)).await.len(), 1);
    emulator.shutdown().await;
    assert!(path.exists(), "state written atomically");
    assert!(!path.with_extension("json.tmp").exists());

    let bus = VirtualBus::new(VirtualBusConfig::default());
    let config_again = config.clone();
    let emulator = spawn(&bus, config);
    let host = bus.attach("host");
    host.send(ext(0x0000_FD01, [0; 8])).await.unwrap();
    host.send(ext(0x0000_FD02, [0; 8])).await.unwrap();
    assert!(collect(&host, Duration::from_millis(50)).await.is_empty());
    let snapshot = emulator.snapshot().await.unwrap();
    assert_eq!((snapshot[0].baud_code, snapshot[0].listening), (2, false));
    // Motor 2 speaks MIT now: deaf to private frames, answers an MIT enable with Response 1.
    assert_eq!((snapshot[1].protocol, snapshot[1].listening), (2, true));
    let mit = |data: [u8; 8]| CanFrame::standard(0x002, &data).unwrap();
    host.send(mit([0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFC]))
        .await
        .unwrap();
    let replies = collect(&host, Duration::from_millis(20)).await;
    assert_eq!(replies.len(), 1, "{replies:?}");
    assert_eq!(
        (replies[0].is_extended(), replies[0].raw_id()),
        (false, u32::from(DEFAULT_HOST_ID))
    );
    assert_eq!(replies[0].data()[0], 2, "motor ID in byte 0");
    assert_eq!(replies[0].data()[6] >> 6, 2, "running");
    // MIT command 8 back to private: Response 2 (the UID) now, private after the power cycle.
    host.send(mit([0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x00, 0xFD]))
        .await
        .unwrap();
    let replies = collect(&host, Duration::from_millis(20)).await;
    assert_eq!(replies.len(), 1, "{replies:?}");
    assert_eq!(
        (replies[0].is_extended(), replies[0].raw_id()),
        (false, 0x002)
    );
    emulator.shutdown().await;
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emulator = spawn(&bus, config_again);
    let host = bus.attach("host");
    host.send(ext(0x0000_FD02, [0; 8])).await.unwrap();
    let replies = collect(&host, Duration::from_millis(20)).await;
    assert_eq!(replies.len(), 1, "private again: {replies:?}");
    assert_eq!(replies[0].raw_id(), 0x0000_02FE);
    emulator.shutdown().await;
    let _ = std::fs::remove_file(path);
}

#[tokio::test(start_paused = true)]
async fn injected_faults_send_type21_on_the_bus() {
    let bus = VirtualBus::new(VirtualBusConfig::default());
    let emulator = spawn(
        &bus,
        RobstrideConfig::new(vec![MotorConfig::new(7, Model::RS04)]),
    );
    let host = bus.attach("host");
    emulator.inject(7, Fault::OverVoltage).await.unwrap();
    let frames = collect(&host, Duration::from_millis(10)).await;
    assert_eq!(frames.len(), 1);
    assert_eq!(frames[0].raw_id(), 0x1500_07FD);
    assert_eq!(frames[0].data(), &[8, 0, 0, 0, 0, 0, 0, 0]);
    emulator.clear(7, Fault::OverVoltage).await.unwrap();
    host.send(ext(0x0400_FD07, [1, 0, 0, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let frames = collect(&host, Duration::from_millis(10)).await;
    // Stop + clear answers with a status frame; the word is clean afterwards.
    assert!(frames.iter().any(|f| f.raw_id() == 0x0200_07FD));
    assert_eq!(emulator.snapshot().await.unwrap()[0].fault_word, 0);
    emulator.shutdown().await;
}

/// A RobStride motor's CAN controller is classic: on a bus that carries CAN FD for other nodes
/// an FD frame on its identifier reaches no motor (no answer, no enable); the classic frame
/// then does.
#[tokio::test(start_paused = true)]
async fn a_can_fd_frame_reaches_no_motor() {
    let bus = VirtualBus::new(VirtualBusConfig {
        data_bitrate_bps: Some(5_000_000),
        ..VirtualBusConfig::default()
    });
    let emulator = spawn(
        &bus,
        RobstrideConfig::new(vec![MotorConfig::new(1, Model::RS03)]),
    );
    let host = bus.attach("host");
    // Type 3 (enable) to motor 1 from host 0xFD, as CAN FD.
    let enable = 0x0300_FD01;
    for flags in [
        FdFlags::default(),
        FdFlags {
            brs: true,
            esi: false,
        },
    ] {
        let id = CanId::extended(enable).unwrap();
        host.send(CanFrame::fd(id, &[0; 8], flags).unwrap())
            .await
            .unwrap();
        let replies = collect(&host, Duration::from_millis(20)).await;
        assert!(replies.is_empty(), "{flags:?}: {replies:?}");
    }
    let snapshot = emulator.snapshot().await.unwrap();
    assert_eq!(snapshot[0].mode, sim::robstride::ModeState::Reset);
    host.send(ext(enable, [0; 8])).await.unwrap();
    let replies = collect(&host, Duration::from_millis(20)).await;
    assert_eq!(replies.len(), 1, "{replies:?}");
    assert!(!replies[0].is_fd());
    let snapshot = emulator.snapshot().await.unwrap();
    assert_eq!(snapshot[0].mode, sim::robstride::ModeState::Run);
    emulator.shutdown().await;
}
