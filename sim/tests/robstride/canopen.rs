//! The CANopen variant (type 25 with F_CMD = 1, then a power cycle): boot-up, NMT, the SDO
//! server over every object the documentation lists, its aborts, the CiA-402 state machine
//! driving the same physics as the private protocol, the 0x6099 watchdog, faults as EMCY,
//! quick stop, homing, and the extended 0xFFF switch back.

use std::f64::consts::{FRAC_PI_2, TAU};
use std::sync::Arc;
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig, VirtualNode};
use bus::{CanBus, CanFrame};
use sim::robstride::{
    Actuator, Fault, ModeState, Model, MotorConfig, RobstrideBus, RobstrideConfig,
};

const NODE: u8 = 5;
const UID: [u8; 8] = [0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77, 0x88];
/// Statusword bits besides the state: voltage enabled (4) and remote (9).
const SW_BASE: u16 = 0x0210;
const TARGET_REACHED: u16 = 0x0400;

fn ext(id: u32, data: [u8; 8]) -> CanFrame {
    CanFrame::extended(id, &data).unwrap()
}

fn std_frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::standard(id, data).unwrap()
}

/// A private-protocol RS03 that was told to speak CANopen (type 25, F_CMD = 1).
fn private_motor() -> Actuator {
    let mut config = MotorConfig::new(NODE, Model::RS03);
    config.uid = Some(UID);
    Actuator::new(config, None, 1_000_000)
}

/// A host's side of one CANopen motor driven tick by tick.
struct Host {
    motor: Actuator,
    /// Every frame the motor sent on its own (ticks), oldest first.
    spontaneous: Vec<CanFrame>,
}

impl Host {
    /// Switch a fresh motor to CANopen, "power cycle" it and let it boot.
    fn booted() -> Self {
        let mut host = Self::power_cycled(switched_to_canopen());
        host.run_ms(1);
        assert_eq!(host.take_spontaneous(), [std_frame(0x705, &[0])], "boot-up");
        host
    }

    fn power_cycled(motor: Actuator) -> Self {
        let saved = motor.persisted();
        Self {
            motor: Actuator::new(motor.config().clone(), Some(&saved), 1_000_000),
            spontaneous: Vec::new(),
        }
    }

    fn run_ms(&mut self, ms: u32) {
        for _ in 0..ms {
            let frames = self.motor.tick();
            self.spontaneous.extend(frames);
        }
    }

    fn take_spontaneous(&mut self) -> Vec<CanFrame> {
        std::mem::take(&mut self.spontaneous)
    }

    /// One SDO request; the single reply's 8 bytes (`None`: no reply at all).
    fn sdo(&mut self, request: [u8; 8]) -> Option<[u8; 8]> {
        let replies = self
            .motor
            .handle_frame(&std_frame(0x600 + u16::from(NODE), &request));
        let sdo: Vec<&CanFrame> = replies
            .iter()
            .filter(|f| f.raw_id() == 0x580 + u32::from(NODE))
            .collect();
        assert!(sdo.len() <= 1, "{replies:?}");
        // EMCY frames that a write causes go with the spontaneous ones.
        self.spontaneous.extend(
            replies
                .iter()
                .filter(|f| f.raw_id() != 0x580 + u32::from(NODE)),
        );
        sdo.first().map(|f| f.data().try_into().unwrap())
    }

    /// Expedited upload: the value (zero-extended) and its size, or the abort code.
    fn read(&mut self, index: u16, sub: u8) -> Result<(u32, usize), u32> {
        let [lo, hi] = index.to_le_bytes();
        let reply = self
            .sdo([0x40, lo, hi, sub, 0, 0, 0, 0])
            .expect("an SDO upload is always answered");
        assert_eq!(&reply[1..4], &[lo, hi, sub], "reply echoes the address");
        match reply[0] {
            0x80 => Err(u32::from_le_bytes(reply[4..8].try_into().unwrap())),
            command => {
                assert_eq!(
                    command & 0xE3,
                    0x43,
                    "expedited, size indicated: {command:#x}"
                );
                let size = 4 - usize::from((command >> 2) & 3);
                let mut value = [0u8; 4];
                value[..size].copy_from_slice(&reply[4..4 + size]);
                Ok((u32::from_le_bytes(value), size))
            }
        }
    }

    fn read_u32(&mut self, index: u16, sub: u8) -> u32 {
        self.read(index, sub)
            .unwrap_or_else(|code| panic!("{index:#06x}:{sub} aborted {code:#010x}"))
            .0
    }

    fn read_i32(&mut self, index: u16) -> i32 {
        let (raw, size) = self.read(index, 0).unwrap();
        // Sign-extend from the object's size.
        let shift = 32 - 8 * size as u32;
        ((raw << shift) as i32) >> shift
    }

    fn statusword(&mut self) -> u16 {
        self.read_u32(0x6041, 0) as u16
    }

    /// Expedited download of `bytes` (size indicated): `Ok` or the abort code.
    fn write(&mut self, index: u16, sub: u8, bytes: &[u8]) -> Result<(), u32> {
        let [lo, hi] = index.to_le_bytes();
        let command = 0x23 | (((4 - bytes.len()) as u8) << 2);
        let mut request = [command, lo, hi, sub, 0, 0, 0, 0];
        request[4..4 + bytes.len()].copy_from_slice(bytes);
        let reply = self
            .sdo(request)
            .expect("an SDO download is always answered");
        assert_eq!(&reply[1..4], &[lo, hi, sub]);
        match reply[0] {
            0x60 => Ok(()),
            0x80 => Err(u32::from_le_bytes(reply[4..8].try_into().unwrap())),
            other => panic!("unexpected SDO reply {other:#x}"),
        }
    }

    fn write_ok(&mut self, index: u16, sub: u8, bytes: &[u8]) {
        if let Err(code) = self.write(index, sub, bytes) {
            panic!("{index:#06x}:{sub} ← {bytes:02x?} aborted {code:#010x}");
        }
    }

    fn controlword(&mut self, word: u16) {
        self.write_ok(0x6040, 0, &word.to_le_bytes());
    }

    fn mode(&mut self, mode: i8) {
        self.write_ok(0x6060, 0, &mode.to_le_bytes());
    }

    fn nmt(&mut self, command: u8, node: u8) -> Vec<CanFrame> {
        self.motor.handle_frame(&std_frame(0x000, &[command, node]))
    }
}

/// Type 25 with F_CMD = 1 from host 0xFD; the motor confirms with type 0 and keeps speaking
/// the private protocol until power-off.
fn switched_to_canopen() -> Actuator {
    let mut motor = private_motor();
    let reply = motor.handle_frame(&ext(0x1900_FD05, [1, 2, 3, 4, 5, 6, 1, 0]));
    assert_eq!(reply.len(), 1);
    assert_eq!(reply[0].raw_id() >> 24, 0, "type-0 confirmation");
    assert_eq!(motor.persisted().protocol, 1);
    assert_eq!(motor.snapshot().protocol, 0);
    motor
}

#[test]
fn after_a_power_cycle_the_motor_boots_as_a_canopen_node_and_ignores_the_private_protocol() {
    let mut host = Host::power_cycled(switched_to_canopen());
    let snapshot = host.motor.snapshot();
    assert_eq!((snapshot.protocol, snapshot.listening), (1, true));
    // Nothing is answered before the node has booted (its first millisecond).
    assert!(host.read_boot_state_silently());
    host.run_ms(1);
    assert_eq!(host.take_spontaneous(), [std_frame(0x705, &[0x00])]);
    host.run_ms(500);
    assert!(
        host.take_spontaneous().is_empty(),
        "no heartbeat unless 0x1017 is set"
    );
    // A private ping (type 0) and enable (type 3) get no answer and do nothing.
    assert!(host
        .motor
        .handle_frame(&ext(0x0000_FD05, [0; 8]))
        .is_empty());
    assert!(host
        .motor
        .handle_frame(&ext(0x0300_FD05, [0; 8]))
        .is_empty());
    assert_eq!(host.motor.snapshot().mode, ModeState::Reset);
    assert_eq!(host.read_u32(0x1000, 0), 0x0002_0192);
}

impl Host {
    /// True when an SDO request before boot-up is ignored (the node is initialising).
    fn read_boot_state_silently(&mut self) -> bool {
        self.sdo([0x40, 0x41, 0x60, 0, 0, 0, 0, 0]).is_none()
    }
}

#[test]
fn nmt_commands_move_the_node_and_the_heartbeat_reports_them() {
    let mut host = Host::booted();
    host.write_ok(0x1017, 0, &100u16.to_le_bytes());
    assert_eq!(host.read_u32(0x1017, 0), 100);
    host.run_ms(250);
    let beats = host.take_spontaneous();
    assert_eq!(
        beats,
        [std_frame(0x705, &[0x7F]), std_frame(0x705, &[0x7F])]
    );

    // Start (to this node): operational.
    assert!(host.nmt(0x01, NODE).is_empty(), "NMT is never answered");
    host.run_ms(100);
    assert_eq!(host.take_spontaneous(), [std_frame(0x705, &[0x05])]);
    // Another node's command changes nothing.
    host.nmt(0x02, NODE + 1);
    host.run_ms(100);
    assert_eq!(host.take_spontaneous(), [std_frame(0x705, &[0x05])]);
    // Stop (broadcast): heartbeat 0x04 and SDO requests unanswered.
    host.nmt(0x02, 0);
    host.run_ms(100);
    assert_eq!(host.take_spontaneous(), [std_frame(0x705, &[0x04])]);
    assert_eq!(host.sdo([0x40, 0x41, 0x60, 0, 0, 0, 0, 0]), None);
    // Pre-operational: SDO served again.
    host.nmt(0x80, NODE);
    host.run_ms(100);
    assert_eq!(host.take_spontaneous(), [std_frame(0x705, &[0x7F])]);
    assert_eq!(host.statusword() & 0x4F, 0x40);
    // Reset communication: silent while it restarts (no SDO served), boot-up 50 ms later,
    // the heartbeat time back to 0.
    assert!(host.nmt(0x82, NODE).is_empty(), "NMT is never answered");
    assert_eq!(host.sdo([0x40, 0x41, 0x60, 0, 0, 0, 0, 0]), None);
    host.run_ms(49);
    assert!(
        host.take_spontaneous().is_empty(),
        "no boot-up before 50 ms"
    );
    host.run_ms(2);
    assert_eq!(host.take_spontaneous(), [std_frame(0x705, &[0x00])]);
    host.run_ms(300);
    assert!(host.take_spontaneous().is_empty());
    assert_eq!(host.read_u32(0x1017, 0), 0);
    // Reset node: boot-up; a drive in quick stop is switched off and keeps its mode.
    host.mode(5);
    host.controlword(15);
    host.controlword(11);
    assert_eq!(host.motor.snapshot().mode, ModeState::Run);
    assert!(host.nmt(0x81, 0).is_empty(), "NMT is never answered");
    assert_eq!(host.motor.snapshot().mode, ModeState::Reset);
    host.run_ms(51);
    assert_eq!(host.take_spontaneous(), [std_frame(0x705, &[0x00])]);
    assert_eq!(host.statusword() & 0x4F, 0x40);
    assert_eq!(
        (host.read_i32(0x6061), host.motor.snapshot().run_mode),
        (5, 5)
    );
    assert_eq!(host.read_u32(0x6040, 0), 0);
    // NMT stop switches an enabled drive off too.
    host.controlword(15);
    host.nmt(0x02, NODE);
    assert_eq!(host.motor.snapshot().mode, ModeState::Reset);
    host.nmt(0x01, NODE);
    assert_eq!(host.statusword() & 0x4F, 0x40);
}

#[test]
fn every_documented_object_reads_with_its_type_and_unit() {
    let mut host = Host::booted();
    // (index, sub, size in bytes, value at power-on)
    let rows: [(u16, u8, usize, u32); 21] = [
        (0x1000, 0, 4, 0x0002_0192),
        (0x1001, 0, 1, 0),
        (0x1017, 0, 2, 0),
        (0x1018, 0, 1, 4),
        (0x1018, 1, 4, 0x556),
        (0x1018, 2, 4, 0x4644),
        (0x1018, 3, 4, 0x500),
        (0x1018, 4, 4, u32::from_le_bytes([0x11, 0x22, 0x33, 0x44])),
        (0x1200, 1, 4, 0x605),
        (0x1200, 2, 4, 0x585),
        (0x603F, 0, 2, 0),
        (0x6040, 0, 2, 0),
        (0x6041, 0, 2, u32::from(0x40 | SW_BASE)),
        (0x6060, 0, 1, 0),
        (0x6061, 0, 1, 0),
        (0x6064, 0, 4, 0),
        (0x606C, 0, 4, 0),
        (0x6071, 0, 2, 0),
        (0x6077, 0, 2, 0),
        (0x6078, 0, 2, 0),
        // 48 V nominal supply in mV.
        (0x6079, 0, 4, 48_000),
    ];
    for (index, sub, size, value) in rows {
        assert_eq!(
            host.read(index, sub),
            Ok((value, size)),
            "{index:#06x}:{sub}"
        );
    }
    let more: [(u16, u8, usize, u32); 5] = [
        (0x607A, 0, 4, 0),
        // vel_max 10 rad/s = 95.5 rpm; acc_set 10 rad/s² in 0.1 rpm/s.
        (0x6081, 0, 4, 955),
        (0x6083, 0, 4, 955),
        (0x6099, 0, 1, 1),
        (0x6099, 1, 4, 0),
    ];
    for (index, sub, size, value) in more {
        assert_eq!(
            host.read(index, sub),
            Ok((value, size)),
            "{index:#06x}:{sub}"
        );
    }
    assert_eq!(host.read(0x60FF, 0), Ok((0, 4)));

    // Writable objects read back what was written, in their units.
    host.write_ok(0x6081, 0, &300u32.to_le_bytes());
    assert_eq!(host.read_u32(0x6081, 0), 300);
    host.write_ok(0x6083, 0, &2000u32.to_le_bytes());
    assert_eq!(host.read_u32(0x6083, 0), 2000);
    host.write_ok(0x6099, 1, &20_000u32.to_le_bytes());
    assert_eq!(host.read_u32(0x6099, 1), 20_000);
    host.write_ok(0x607A, 0, &(-4096i32).to_le_bytes());
    assert_eq!(host.read_i32(0x607A), -4096);
    host.write_ok(0x60FF, 0, &(-150i32).to_le_bytes());
    assert_eq!(host.read_i32(0x60FF), -150);
    host.write_ok(0x6071, 0, &(-250i16).to_le_bytes());
    assert_eq!(host.read_i32(0x6071), -250);
    host.mode(5);
    assert_eq!((host.read_i32(0x6060), host.read_i32(0x6061)), (5, 5));
    assert_eq!(host.motor.snapshot().run_mode, 5);
    host.controlword(6);
    assert_eq!(host.read_u32(0x6040, 0), 6);
    // A size-less expedited download (0x22) takes the object's own size.
    assert_eq!(
        host.sdo([0x22, 0x17, 0x10, 0, 50, 0, 0, 0]).unwrap()[0],
        0x60
    );
    assert_eq!(host.read_u32(0x1017, 0), 50);
}

#[test]
fn what_the_documentation_leaves_out_is_aborted_never_silent() {
    let mut host = Host::booted();
    let abort = |host: &mut Host, request: [u8; 8]| {
        let reply = host.sdo(request).expect("answered");
        assert_eq!(reply[0], 0x80, "{request:02x?} → {reply:02x?}");
        assert_eq!(reply[1..4], request[1..4], "abort names the object");
        u32::from_le_bytes(reply[4..8].try_into().unwrap())
    };
    // Unknown objects, including the PDO parameters (no PDOs) and 0x6502.
    for index in [
        0x2000u16, 0x1400, 0x1600, 0x1800, 0x1A00, 0x6502, 0x6084, 0x1008,
    ] {
        assert_eq!(host.read(index, 0), Err(0x0602_0000), "{index:#06x}");
    }
    // Unknown subindices.
    assert_eq!(host.read(0x6041, 1), Err(0x0609_0011));
    assert_eq!(host.read(0x1018, 5), Err(0x0609_0011));
    assert_eq!(host.read(0x6099, 2), Err(0x0609_0011));
    // Writes to read-only objects.
    assert_eq!(host.write(0x6041, 0, &[0, 0]), Err(0x0601_0002));
    assert_eq!(host.write(0x6064, 0, &[0, 0, 0, 0]), Err(0x0601_0002));
    assert_eq!(host.write(0x1018, 1, &[0, 0, 0, 0]), Err(0x0601_0002));
    // Values out of range: modes outside 1/3/4/5/6, speeds past the model's ±20 rad/s
    // (1910 × 0.1 rpm), the watchdog past 100000 ticks, torque past the current range.
    for mode in [0i8, 2, 7, 8, -1] {
        assert_eq!(host.write(0x6060, 0, &[mode as u8]), Err(0x0609_0030));
    }
    assert_eq!(
        host.write(0x60FF, 0, &2000i32.to_le_bytes()),
        Err(0x0609_0030)
    );
    assert_eq!(
        host.write(0x6081, 0, &2000u32.to_le_bytes()),
        Err(0x0609_0030)
    );
    assert_eq!(
        host.write(0x6099, 1, &100_001u32.to_le_bytes()),
        Err(0x0609_0030)
    );
    assert_eq!(
        host.write(0x6071, 0, &6000i16.to_le_bytes()),
        Err(0x0609_0030)
    );
    assert_eq!(host.read_i32(0x60FF), 0, "a refused value is not stored");
    // A stated size that is not the object's.
    assert_eq!(host.write(0x6040, 0, &[6, 0, 0, 0]), Err(0x0607_0010));
    assert_eq!(host.write(0x6060, 0, &[5, 0]), Err(0x0607_0010));
    // Segmented download: the size decides the code; block transfers and stray segments
    // are invalid commands.
    assert_eq!(
        abort(&mut host, [0x21, 0x7A, 0x60, 0, 9, 0, 0, 0]),
        0x0607_0010
    );
    assert_eq!(
        abort(&mut host, [0x21, 0x7A, 0x60, 0, 4, 0, 0, 0]),
        0x0504_0001
    );
    assert_eq!(
        abort(&mut host, [0x20, 0x64, 0x60, 0, 0, 0, 0, 0]),
        0x0601_0002
    );
    assert_eq!(
        abort(&mut host, [0x60, 0x41, 0x60, 0, 0, 0, 0, 0]),
        0x0504_0001
    );
    assert_eq!(
        abort(&mut host, [0x00, 0x41, 0x60, 0, 0, 0, 0, 0]),
        0x0504_0001
    );
    assert_eq!(
        abort(&mut host, [0xC0, 0x41, 0x60, 0, 0, 0, 0, 0]),
        0x0504_0001
    );
    assert_eq!(
        abort(&mut host, [0xA4, 0x41, 0x60, 0, 0, 0, 0, 0]),
        0x0504_0001
    );
    // A frame shorter than 8 bytes.
    let short = host
        .motor
        .handle_frame(&std_frame(0x605, &[0x40, 0x41, 0x60, 0]));
    assert_eq!(short.len(), 1);
    assert_eq!(&short[0].data()[4..], &0x0504_0001u32.to_le_bytes());
    // A client's abort is not answered.
    assert_eq!(host.sdo([0x80, 0x41, 0x60, 0, 0, 0, 0, 0]), None);
    // The mode is refused while the drive runs (state prevents).
    host.mode(3);
    host.controlword(15);
    assert_eq!(host.write(0x6060, 0, &[5]), Err(0x0800_0022));
    assert_eq!(host.read_i32(0x6061), 3);
    // Other nodes' requests and PDO frames are ignored.
    assert!(host
        .motor
        .handle_frame(&std_frame(0x606, &[0x40, 0x41, 0x60, 0, 0, 0, 0, 0]))
        .is_empty());
    assert!(host
        .motor
        .handle_frame(&std_frame(0x205, &[0x0F, 0]))
        .is_empty());
}

#[test]
fn enable_6_7_15_then_csp_moves_the_joint_to_the_target() {
    let mut host = Host::booted();
    host.mode(5);
    for (word, state) in [(6u16, 0x21u16), (7, 0x23), (15, 0x27)] {
        host.controlword(word);
        assert_eq!(host.statusword() & 0x6F, state, "after controlword {word}");
    }
    assert_eq!(host.motor.snapshot().mode, ModeState::Run);
    // Enabling holds the present position: target = actual, target reached.
    assert_eq!(host.statusword(), 0x27 | SW_BASE | TARGET_REACHED);
    assert_eq!(host.read_i32(0x607A), host.read_i32(0x6064));
    // A quarter turn: 4096 counts.
    host.write_ok(0x607A, 0, &4096i32.to_le_bytes());
    host.run_ms(50);
    assert_eq!(host.statusword() & TARGET_REACHED, 0, "moving");
    assert!(
        host.read_i32(0x606C) > 0,
        "velocity actual positive while moving"
    );
    host.run_ms(2000);
    let counts = host.read_i32(0x6064);
    assert!((counts - 4096).abs() <= 45, "position actual {counts}");
    assert_ne!(host.statusword() & TARGET_REACHED, 0);
    let angle = host.motor.snapshot().angle_rad;
    assert!((angle - FRAC_PI_2).abs() < 0.02, "plant angle {angle}");
    // Disable (1): torque off.
    host.controlword(1);
    assert_eq!(host.statusword() & 0x4F, 0x40);
    assert_eq!(host.motor.snapshot().mode, ModeState::Reset);
    host.mode(1);
    assert_eq!(host.motor.snapshot().run_mode, 1);
}

#[test]
fn profile_position_follows_the_profile_velocity() {
    let mut host = Host::booted();
    host.mode(1);
    // 30 rpm profile speed (3.14 rad/s), steep acceleration.
    host.write_ok(0x6081, 0, &300u32.to_le_bytes());
    host.write_ok(0x6083, 0, &5000u32.to_le_bytes());
    host.controlword(15);
    host.write_ok(0x607A, 0, &16384i32.to_le_bytes());
    host.run_ms(1000);
    let velocity = host.read_i32(0x606C);
    assert!(
        (velocity - 300).abs() <= 15,
        "cruising at {velocity} × 0.1 rpm"
    );
    host.run_ms(2000);
    let counts = host.read_i32(0x6064);
    assert!((counts - 16384).abs() <= 45, "one turn: {counts}");
    assert!((host.motor.snapshot().angle_rad - TAU).abs() < 0.02);
}

#[test]
fn velocity_mode_reaches_the_target_velocity() {
    let mut host = Host::booted();
    host.mode(3);
    host.write_ok(0x60FF, 0, &300i32.to_le_bytes());
    // 15 directly from switch on disabled.
    host.controlword(15);
    assert_eq!(host.statusword() & 0x6F, 0x27);
    host.run_ms(1000);
    let velocity = host.read_i32(0x606C);
    assert!((velocity - 300).abs() <= 5, "velocity actual {velocity}");
    let speed = host.motor.snapshot().speed_rad_s;
    assert!(
        (speed - 300.0 * TAU / 600.0).abs() < 0.05,
        "plant speed {speed}"
    );
    assert_ne!(host.statusword() & TARGET_REACHED, 0);
    // A new target applies at once.
    host.write_ok(0x60FF, 0, &(-100i32).to_le_bytes());
    host.run_ms(1000);
    assert!((host.read_i32(0x606C) + 100).abs() <= 5);
}

#[test]
fn torque_mode_produces_the_target_torque() {
    let mut host = Host::booted();
    host.mode(4);
    host.controlword(15);
    // 5 % of the RS03's rated 20 N·m = 1 N·m → iq = 1 / 2.36 A.
    host.write_ok(0x6071, 0, &50i16.to_le_bytes());
    host.run_ms(20);
    assert_eq!(host.read_i32(0x6077), 50);
    let current_ma = host.read_i32(0x6078);
    assert!(
        (current_ma - 424).abs() <= 1,
        "current actual {current_ma} mA"
    );
    let snapshot = host.motor.snapshot();
    assert!((snapshot.torque_nm - 1.0).abs() < 1e-6);
    // The disc (1 kg, 0.1 m: 5e-3 kg·m²) accelerates at about 200 rad/s².
    assert!(
        snapshot.speed_rad_s > 3.0 && snapshot.speed_rad_s < 4.5,
        "speed after 20 ms {}",
        snapshot.speed_rad_s
    );
    assert!(host.read_i32(0x606C) > 0);
}

#[test]
fn watchdog_expiry_is_a_fault_reported_by_emcy_and_cleared_by_a_fault_reset() {
    let mut host = Host::booted();
    // 2000 ticks = 0.1 s.
    host.write_ok(0x6099, 1, &2000u32.to_le_bytes());
    host.mode(3);
    host.write_ok(0x60FF, 0, &100i32.to_le_bytes());
    host.controlword(15);
    host.run_ms(90);
    assert!(host.take_spontaneous().is_empty());
    // Any SDO request feeds the watchdog.
    assert_eq!(host.statusword() & 0x6F, 0x27);
    host.run_ms(90);
    assert_eq!(host.motor.snapshot().mode, ModeState::Run);
    host.run_ms(30);
    assert_eq!(host.motor.snapshot().mode, ModeState::Reset);
    // EMCY: 0x8130, error register generic + communication, fault word 0.
    assert_eq!(
        host.take_spontaneous(),
        [std_frame(0x085, &[0x30, 0x81, 0x11, 0, 0, 0, 0, 0])]
    );
    assert_eq!(host.statusword() & 0x4F, 0x08);
    assert_eq!(host.read_u32(0x603F, 0), 0x8130);
    assert_eq!(host.read_u32(0x1001, 0), 0x11);
    // Enable is ignored in Fault; a fault reset (bit 7 rising) clears it.
    host.controlword(15);
    assert_eq!(host.statusword() & 0x4F, 0x08);
    host.controlword(0x80);
    assert_eq!(host.statusword() & 0x4F, 0x40);
    assert_eq!(host.read_u32(0x603F, 0), 0);
    assert_eq!(host.take_spontaneous(), [std_frame(0x085, &[0; 8])]);
    host.controlword(15);
    assert_eq!(host.motor.snapshot().mode, ModeState::Run);
}

#[test]
fn a_latched_fault_stops_the_drive_with_emcy_not_a_type21_frame() {
    let mut host = Host::booted();
    host.mode(5);
    host.controlword(15);
    let sent = host.motor.inject(Fault::OverTemperature);
    assert_eq!(
        sent, None,
        "no private-protocol fault frame on a CANopen bus"
    );
    host.run_ms(1);
    let emcy = host.take_spontaneous();
    assert_eq!(emcy.len(), 1);
    assert_eq!(emcy[0].raw_id(), 0x085);
    // 0x4310 motor over-temperature, register generic + temperature, fault word bit 0.
    assert_eq!(emcy[0].data(), &[0x10, 0x43, 0x09, 0x01, 0, 0, 0, 0]);
    assert_eq!(host.statusword() & 0x4F, 0x08);
    assert_ne!(
        host.statusword() & 0x80,
        0,
        "warning bit: over-temperature warning"
    );
    assert_eq!(host.motor.snapshot().mode, ModeState::Reset);
    // Still hot: the reset is refused.
    host.controlword(0x80);
    assert_eq!(host.statusword() & 0x4F, 0x08);
    host.motor.remove_cause(Fault::OverTemperature);
    host.controlword(0);
    host.controlword(0x80);
    assert_eq!(host.statusword() & 0x4F, 0x40);
}

#[test]
fn quick_stop_brakes_to_standstill_and_enable_resumes() {
    let mut host = Host::booted();
    host.mode(3);
    host.write_ok(0x60FF, 0, &300i32.to_le_bytes());
    host.controlword(15);
    host.run_ms(1000);
    assert!(host.motor.snapshot().speed_rad_s > 3.0);
    host.controlword(11);
    assert_eq!(host.statusword() & 0x6F, 0x07);
    // acc_rad 20 rad/s² brings 3.14 rad/s to rest in about 0.16 s.
    host.run_ms(400);
    let snapshot = host.motor.snapshot();
    assert!(
        snapshot.speed_rad_s.abs() < 0.05,
        "speed {}",
        snapshot.speed_rad_s
    );
    assert_eq!(snapshot.mode, ModeState::Run, "holding zero speed");
    assert_ne!(host.statusword() & TARGET_REACHED, 0);
    assert_eq!(
        host.read_i32(0x6061),
        3,
        "the mode display keeps the host's mode"
    );
    // Enable operation again: back to the target velocity.
    host.controlword(15);
    assert_eq!(host.statusword() & 0x6F, 0x27);
    host.run_ms(1000);
    assert!((host.read_i32(0x606C) - 300).abs() <= 5);
    // Quick stop, then disable voltage: torque off.
    host.controlword(11);
    host.controlword(0);
    assert_eq!(host.statusword() & 0x4F, 0x40);
    assert_eq!(host.motor.snapshot().mode, ModeState::Reset);
}

#[test]
fn homing_sets_the_present_position_as_zero_and_keeps_it() {
    let mut host = Host::booted();
    host.mode(5);
    host.controlword(15);
    host.write_ok(0x607A, 0, &2048i32.to_le_bytes());
    host.run_ms(1500);
    let before = host.read_i32(0x6064);
    assert!((before - 2048).abs() <= 45);
    host.controlword(6);
    host.mode(6);
    host.controlword(15);
    let status = host.statusword();
    assert_ne!(status & 0x1000, 0, "homing attained");
    assert_ne!(status & TARGET_REACHED, 0);
    assert!(host.read_i32(0x6064).abs() <= 1);
    host.run_ms(500);
    assert!(host.read_i32(0x6064).abs() <= 45, "holds the new zero");
    let zero = host.motor.persisted().zero_offset_rad;
    assert!(
        (zero - 2048.0 * TAU / 16384.0).abs() < 0.02,
        "zero kept: {zero}"
    );
}

#[test]
fn the_fff_frame_switches_back_after_the_next_power_cycle_and_answers_with_the_uid() {
    let mut host = Host::booted();
    // Wrong magic or F_CMD: ignored.
    assert!(host
        .motor
        .handle_frame(&ext(0xFFF, [1, 2, 3, 4, 5, 7, 0, 0]))
        .is_empty());
    assert!(host
        .motor
        .handle_frame(&ext(0xFFF, [1, 2, 3, 4, 5, 6, 3, 0]))
        .is_empty());
    let reply = host
        .motor
        .handle_frame(&CanFrame::extended(0xFFF, &[1, 2, 3, 4, 5, 6, 0]).unwrap());
    assert_eq!(reply, [std_frame(u16::from(NODE), &UID)]);
    assert_eq!(host.motor.persisted().protocol, 0);
    // Still CANopen until power-off.
    assert_eq!(host.statusword() & 0x4F, 0x40);
    let mut private = Host::power_cycled(host.motor);
    private.run_ms(5);
    assert!(private.take_spontaneous().is_empty(), "no boot-up");
    let ping = private.motor.handle_frame(&ext(0x0000_FD05, [0; 8]));
    assert_eq!(ping.len(), 1);
    assert_eq!(ping[0].raw_id(), 0x0000_05FE);
    assert_eq!(ping[0].data(), &UID);
    assert!(private
        .motor
        .handle_frame(&std_frame(0x605, &[0x40, 0x41, 0x60, 0, 0, 0, 0, 0]))
        .is_empty());
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

#[tokio::test(start_paused = true)]
async fn on_the_bus_the_state_file_carries_the_switch_and_11_bit_frames_reach_the_node() {
    let dir = std::env::temp_dir().join(format!("armhil-canopen-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("state.json");
    let _ = std::fs::remove_file(&path);
    let mut motor = MotorConfig::new(NODE, Model::RS03);
    motor.uid = Some(UID);
    let mut config = RobstrideConfig::new(vec![motor]);
    config.state_file = Some(path.clone());

    let bus = VirtualBus::new(VirtualBusConfig::default());
    let node: Arc<dyn CanBus> = Arc::new(bus.attach("emulator"));
    let emulator = RobstrideBus::spawn(node, config.clone()).unwrap();
    let host = bus.attach("host");
    host.send(ext(0x1900_FD05, [1, 2, 3, 4, 5, 6, 1, 0]))
        .await
        .unwrap();
    assert_eq!(collect(&host, Duration::from_millis(20)).await.len(), 1);
    emulator.shutdown().await;

    let bus = VirtualBus::new(VirtualBusConfig::default());
    let host = bus.attach("host");
    let node: Arc<dyn CanBus> = Arc::new(bus.attach("emulator"));
    let emulator = RobstrideBus::spawn(node, config).unwrap();
    let boot = collect(&host, Duration::from_millis(20)).await;
    assert_eq!(boot, [std_frame(0x705, &[0])]);
    host.send(std_frame(0x605, &[0x40, 0x41, 0x60, 0, 0, 0, 0, 0]))
        .await
        .unwrap();
    let reply = collect(&host, Duration::from_millis(20)).await;
    assert_eq!(
        reply,
        [std_frame(0x585, &[0x4B, 0x41, 0x60, 0, 0x50, 0x02, 0, 0])]
    );
    let snapshot = emulator.snapshot().await.unwrap();
    assert_eq!((snapshot[0].protocol, snapshot[0].listening), (1, true));
    emulator.shutdown().await;
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn random_frames_never_panic_and_every_sdo_request_is_answered_once() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand::rngs::SmallRng::seed_from_u64(20);
    let mut host = Host::booted();
    for step in 0..20_000 {
        let len = rng.random_range(0..=8);
        let mut data = [0u8; 8];
        rng.fill(&mut data[..len]);
        // Mostly this node's SDO channel and NMT, sometimes anything at all.
        let id: u16 = match rng.random_range(0..10) {
            0..=6 => 0x605,
            7 => 0x000,
            _ => rng.random_range(0..0x800),
        };
        if id == 0x000 && len >= 1 && data[0] == 0x02 {
            // Keep the node talking: no NMT stop in this run.
            data[0] = 0x01;
        }
        let frame = std_frame(id, &data[..len]);
        let replies = host.motor.handle_frame(&frame);
        if id == 0x605 {
            let answers = replies.iter().filter(|f| f.raw_id() == 0x585).count();
            let client_abort = len == 8 && data[0] >> 5 == 4;
            assert_eq!(
                answers,
                usize::from(!client_abort),
                "step {step}: {frame} → {replies:?}"
            );
        }
        if step % 7 == 0 {
            host.run_ms(1);
        }
    }
    let snapshot = host.motor.snapshot();
    assert!(snapshot.angle_rad.is_finite() && snapshot.speed_rad_s.is_finite());
}
