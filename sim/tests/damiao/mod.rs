//! The Damiao (DM) motor emulator: the four control modes tick by tick, the registers, the
//! errors and the CAN timeout, malformed frames, the bus runner under a paused clock, and the
//! shared fixtures (`fixtures/damiao/`).

mod conformance;
mod faults;
mod malformed;
mod modes;
mod on_bus;
mod registers;

use bus::CanFrame;
use sim::damiao::codec::{register_payload, Feedback, MitCommand, RegisterCmd, Special};
use sim::damiao::{DamiaoMotor, Model, MotorConfig};

/// A motor on the default rig (1 kg, 0.1 m disc), ESC_ID `esc` and MST_ID `esc + 0x10`.
fn motor(esc: u16, model: Model) -> DamiaoMotor {
    DamiaoMotor::new(MotorConfig::new(esc, model))
}

/// A classic standard frame.
fn std_frame(id: u16, data: &[u8]) -> CanFrame {
    CanFrame::standard(id, data).unwrap()
}

/// The only frame in `replies`.
fn one(replies: Vec<CanFrame>) -> CanFrame {
    assert_eq!(replies.len(), 1, "expected one reply, got {replies:?}");
    replies[0]
}

/// `frame` decoded as a feedback frame over `m`'s ranges, after checking it is one: on
/// MST_ID, DLC 8, with the low nibble of ESC_ID.
fn decode(m: &DamiaoMotor, frame: CanFrame) -> Feedback {
    assert_eq!(frame.raw_id(), u32::from(m.mst_id()), "{frame}");
    let data: [u8; 8] = frame.data().try_into().expect("DLC 8");
    let feedback = Feedback::unpack(&data, &m.registers().ranges());
    assert_eq!(u16::from(feedback.id_nibble), m.esc_id() & 0x0F, "{frame}");
    feedback
}

/// Send `frame`; its one reply, decoded as feedback.
fn answer(m: &mut DamiaoMotor, frame: CanFrame) -> Feedback {
    let reply = one(m.handle_frame(&frame));
    decode(m, reply)
}

/// Send a special command; its one feedback frame, decoded.
fn special(m: &mut DamiaoMotor, command: Special) -> Feedback {
    let reply = one(m.handle_frame(&std_frame(m.esc_id(), &command.payload())));
    decode(m, reply)
}

/// A 0xCC refresh; the feedback it gets, decoded.
fn refresh(m: &mut DamiaoMotor) -> Feedback {
    let reply = one(m.handle_frame(&register(m.esc_id(), RegisterCmd::Refresh, 0, [0; 4])));
    decode(m, reply)
}

/// A register request on 0x7FF.
fn register(esc: u16, cmd: RegisterCmd, rid: u8, value: [u8; 4]) -> CanFrame {
    std_frame(0x7FF, &register_payload(esc, cmd.byte(), rid, value))
}

/// Write `value` to register `rid`; the replies.
fn write(m: &mut DamiaoMotor, rid: u8, value: [u8; 4]) -> Vec<CanFrame> {
    m.handle_frame(&register(m.esc_id(), RegisterCmd::Write, rid, value))
}

/// Select a control mode by writing CTRL_MODE (1 MIT, 2 pos-vel, 3 velocity, 4 force-pos).
fn set_mode(m: &mut DamiaoMotor, mode: u32) {
    let echo = one(write(m, 10, mode.to_le_bytes()));
    assert_eq!(&echo.data()[4..], mode.to_le_bytes(), "{echo}");
}

/// Send an MIT setpoint; the replies.
fn mit(m: &mut DamiaoMotor, command: MitCommand) -> Vec<CanFrame> {
    let data = command.pack(&m.registers().ranges());
    m.handle_frame(&std_frame(m.esc_id(), &data))
}

/// Run `ms` ticks.
fn run(m: &mut DamiaoMotor, ms: u32) {
    for _ in 0..ms {
        assert!(m.tick().is_empty(), "a Damiao motor sends nothing unasked");
    }
}
