//! The CANopen variant of the firmware (after type 25 with F_CMD = 1 and a power cycle): a
//! CiA-301 slave with the CiA-402 drive objects the RobStride documentation lists, driving
//! the same firmware core (enable and stop, run modes, references, the CAN watchdog, faults,
//! physics) as the private protocol.
//!
//! - [`nmt`]: NMT states and commands, boot-up and heartbeat.
//! - [`sdo`]: the SDO server's frames (expedited transfers and aborts).
//! - [`cia402`]: the drive state machine and statusword patterns.
//! - [`objects`]: the object dictionary, units, and reads and writes against the core.
//!
//! Choices where the documentation is silent (docs/protocols/robstride.md §13): no PDOs
//! (every object is reached by SDO; PDO frames are ignored and the PDO parameter objects
//! answered "object does not exist"); anything not listed is answered with an SDO abort; a
//! fault or watchdog expiry sends an EMCY frame; quick stop brakes on the velocity ramp and
//! holds zero speed.

mod cia402;
mod nmt;
mod objects;
mod sdo;

use bus::CanFrame;

use self::cia402::{Command, DriveState};
use self::nmt::{NmtCommand, NmtState};
use self::sdo::{Abort, Address, Request};
use super::{protocol_accepted, Actuator, ModeState};
use crate::robstride::faults::Fault;
use crate::robstride::params::index;

/// The protocol byte (type 25 F_CMD, state file) of the CANopen variant.
pub(super) const PROTOCOL_CANOPEN: u8 = 1;
/// Extended ID of the "leave CANopen" frame (data `01 02 03 04 05 06 F_CMD`).
const SWITCH_PROTOCOL_ID: u32 = 0xFFF;
/// Magic prefix of the switch frame.
const SWITCH_MAGIC: [u8; 6] = [1, 2, 3, 4, 5, 6];
/// Base of the EMCY COB-ID: 0x080 + node-ID.
const EMCY_BASE: u16 = 0x080;
/// Error code of a watchdog expiry (CiA-301 "life guard error or heartbeat error").
const WATCHDOG_ERROR_CODE: u16 = 0x8130;

/// How long a node takes to restart after an NMT reset (node or communication) before its
/// boot-up, ms: an estimate (neither CiA 301 nor RobStride gives a figure; CANopen devices
/// take tens to hundreds of milliseconds to restart their application). Answering at once
/// was faster than any device, and a real master (python-canopen's `wait_for_bootup`, which
/// starts listening after it sent the reset) missed the boot-up.
const RESET_BOOT_MS: u32 = 50;

/// A mode of operation, in this drive's own numbering (spec: 1 PP, 3 velocity, 4 torque,
/// 5 CSP, 6 homing; DS402 would call CSP 8).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Mode {
    /// 0: none selected yet (power-on with a run mode that has no CANopen number).
    None,
    /// 1: profile position → run_mode 1.
    ProfilePosition,
    /// 3: velocity → run_mode 2.
    Velocity,
    /// 4: torque → run_mode 3 (current), iq = torque / Kt.
    Torque,
    /// 5: cyclic synchronous position → run_mode 5.
    CyclicPosition,
    /// 6: "homing" = the present position becomes zero; then holds it (run_mode 5).
    Homing,
}

impl Mode {
    /// The value of 0x6060/0x6061.
    pub(super) fn code(self) -> i8 {
        match self {
            Mode::None => 0,
            Mode::ProfilePosition => 1,
            Mode::Velocity => 3,
            Mode::Torque => 4,
            Mode::CyclicPosition => 5,
            Mode::Homing => 6,
        }
    }

    /// A mode a host may select (0 is not one).
    pub(super) fn from_code(code: i64) -> Option<Self> {
        match code {
            1 => Some(Mode::ProfilePosition),
            3 => Some(Mode::Velocity),
            4 => Some(Mode::Torque),
            5 => Some(Mode::CyclicPosition),
            6 => Some(Mode::Homing),
            _ => None,
        }
    }

    /// The mode the firmware powers on in, from its run_mode.
    fn from_run_mode(run_mode: u8) -> Self {
        match run_mode {
            1 => Mode::ProfilePosition,
            2 => Mode::Velocity,
            3 => Mode::Torque,
            5 => Mode::CyclicPosition,
            _ => Mode::None,
        }
    }

    /// The firmware run_mode (0x7005) that carries it out.
    pub(super) fn run_mode(self) -> u8 {
        match self {
            Mode::None => 0,
            Mode::ProfilePosition => 1,
            Mode::Velocity => 2,
            Mode::Torque => 3,
            Mode::CyclicPosition | Mode::Homing => 5,
        }
    }
}

/// The CANopen side of one motor: NMT and drive state, the target objects, heartbeat.
#[derive(Debug, Clone)]
pub(super) struct CanopenNode {
    nmt: NmtState,
    drive: DriveState,
    mode: Mode,
    controlword: u16,
    error_code: u16,
    watchdog_expired: bool,
    homed: bool,
    target_position_counts: i64,
    target_velocity_deci_rpm: i64,
    target_torque_permille: i16,
    heartbeat_ms: u16,
    heartbeat_elapsed_ms: u32,
    /// Milliseconds until a node restarting after an NMT reset sends its boot-up (0 at
    /// power-on: the first step sends it).
    boot_in_ms: u32,
    /// Frames produced outside a reply (EMCY), sent with the next reply or tick.
    outbox: Vec<CanFrame>,
}

impl CanopenNode {
    /// A node at power-on: boot-up still to send.
    pub(super) fn new() -> Self {
        Self {
            nmt: NmtState::Initialising,
            drive: DriveState::SwitchOnDisabled,
            mode: Mode::None,
            controlword: 0,
            error_code: 0,
            watchdog_expired: false,
            homed: false,
            target_position_counts: 0,
            target_velocity_deci_rpm: 0,
            target_torque_permille: 0,
            heartbeat_ms: 0,
            heartbeat_elapsed_ms: 0,
            boot_in_ms: 0,
            outbox: Vec::new(),
        }
    }
}

fn standard(id: u16, data: &[u8]) -> Option<CanFrame> {
    CanFrame::standard(id, data).ok()
}

// Frames and time.
impl Actuator {
    /// React to a frame while speaking CANopen: NMT (0x000), SDO requests (0x600 + node-ID)
    /// and the extended 0xFFF protocol switch. Everything else (PDOs, SYNC, other nodes) is
    /// ignored.
    pub(super) fn handle_canopen_frame(&mut self, frame: &CanFrame) -> Vec<CanFrame> {
        let mut out = Vec::new();
        let data = frame.data();
        if frame.is_extended() {
            if frame.raw_id() == SWITCH_PROTOCOL_ID {
                out.extend(self.canopen_switch_protocol(data));
            }
        } else if frame.raw_id() == u32::from(nmt::NMT_COB_ID) {
            if let Some(command) = nmt::decode(data, self.can_id) {
                self.since_command_s = 0.0;
                out.extend(self.nmt_command(command));
            }
        } else if frame.raw_id() == u32::from(sdo::RX_BASE) + u32::from(self.can_id)
            && self.canopen.nmt.serves_sdo()
        {
            self.since_command_s = 0.0;
            if let Some(reply) = self.serve_sdo(data) {
                out.extend(standard(sdo::TX_BASE + u16::from(self.can_id), &reply));
            }
        }
        out.append(&mut self.canopen.outbox);
        out
    }

    /// Each millisecond: boot-up once, faults and watchdog expiry into the Fault state (with
    /// an EMCY frame), and the heartbeat.
    pub(super) fn canopen_tick(&mut self) -> Vec<CanFrame> {
        let mut out = Vec::new();
        if self.canopen.nmt == NmtState::Initialising {
            if self.canopen.boot_in_ms > 0 {
                self.canopen.boot_in_ms -= 1;
            } else {
                if self.canopen.mode == Mode::None {
                    // At power-on the mode comes from the 0x70xx table; a reset node keeps its.
                    self.canopen.mode = Mode::from_run_mode(self.run_mode());
                }
                out.extend(self.boot_up());
            }
        }
        if self.canopen.drive != DriveState::Fault {
            if self.fault_word != 0 {
                self.enter_fault(fault_error_code(self.fault_word));
            } else if cia402::energised(self.canopen.drive) && self.mode != ModeState::Run {
                // Only the CAN watchdog (0x6099 sub 1) stops a running motor without a fault.
                tracing::info!(motor = self.can_id, "robstride CANopen: watchdog expired");
                self.canopen.watchdog_expired = true;
                self.enter_fault(WATCHDOG_ERROR_CODE);
            }
        }
        let node = &mut self.canopen;
        if node.heartbeat_ms > 0 {
            node.heartbeat_elapsed_ms += 1;
            if node.heartbeat_elapsed_ms >= u32::from(node.heartbeat_ms) {
                node.heartbeat_elapsed_ms = 0;
                let state = node.nmt.heartbeat_byte();
                out.extend(standard(
                    nmt::ERROR_CONTROL_BASE + u16::from(self.can_id),
                    &[state],
                ));
            }
        }
        out.append(&mut self.canopen.outbox);
        out
    }

    /// The node restarts: silent (Initialising: no SDO served) until its boot-up, `ms` from
    /// now, sent by [`Actuator::canopen_tick`].
    fn restart_after(&mut self, ms: u32) {
        self.canopen.nmt = NmtState::Initialising;
        self.canopen.boot_in_ms = ms;
    }

    fn boot_up(&mut self) -> Option<CanFrame> {
        self.canopen.nmt = NmtState::PreOperational;
        standard(nmt::ERROR_CONTROL_BASE + u16::from(self.can_id), &[0x00])
    }

    fn nmt_command(&mut self, command: NmtCommand) -> Option<CanFrame> {
        match command {
            NmtCommand::Start => self.canopen.nmt = NmtState::Operational,
            NmtCommand::EnterPreOperational => self.canopen.nmt = NmtState::PreOperational,
            NmtCommand::Stop => {
                // Without SDO the host cannot command the drive any more: torque off.
                self.canopen.nmt = NmtState::Stopped;
                if cia402::energised(self.canopen.drive) {
                    self.disable_drive(DriveState::SwitchOnDisabled);
                }
            }
            NmtCommand::ResetNode => {
                // The application restarts: torque off, latched faults whose cause is gone
                // cleared, the node's objects back to their power-on values. The mode lives
                // in the 0x70xx table (run_mode) and is kept.
                let mode = self.canopen.mode;
                self.disable_drive(DriveState::SwitchOnDisabled);
                self.clear_faults();
                self.canopen = CanopenNode::new();
                self.canopen.mode = mode;
                self.restart_after(RESET_BOOT_MS);
            }
            NmtCommand::ResetCommunication => {
                self.canopen.heartbeat_ms = 0;
                self.canopen.heartbeat_elapsed_ms = 0;
                self.restart_after(RESET_BOOT_MS);
            }
        }
        None
    }

    /// The extended 0xFFF frame: store the protocol for the next power-on and answer on the
    /// standard ID = motor ID with the MCU UID (a broadcast: every CANopen motor answers).
    fn canopen_switch_protocol(&mut self, data: &[u8]) -> Option<CanFrame> {
        if data.len() < 7 || data[..6] != SWITCH_MAGIC || !protocol_accepted(data[6]) {
            return None;
        }
        tracing::info!(
            motor = self.can_id,
            protocol = data[6],
            "robstride CANopen: protocol switch stored for the next power-on"
        );
        self.pending_protocol = data[6];
        self.persist_requested = true;
        standard(u16::from(self.can_id), &self.uid)
    }

    /// The answer to an SDO request; `None` for a client's abort, which is never answered.
    fn serve_sdo(&mut self, data: &[u8]) -> Option<[u8; 8]> {
        let reply = match sdo::parse(data) {
            Request::Upload(at) => match objects::lookup(at) {
                Ok(object) => {
                    let value = self.read_object(object);
                    sdo::upload_response(at, &object.data_type().encode(value))
                }
                Err(why) => sdo::abort(at, why),
            },
            Request::Download { at, data, size } => match self.sdo_download(at, data, size) {
                Ok(()) => sdo::download_response(at),
                Err(why) => sdo::abort(at, why),
            },
            Request::SegmentedDownload { at, size } => {
                // Every object fits an expedited transfer; say why this one is refused.
                let why = match objects::lookup(at) {
                    Err(why) => why,
                    Ok(object) if !object.writable() => Abort::WriteOfReadOnly,
                    Ok(object) if size.is_some_and(|n| n as usize != object.data_type().size()) => {
                        Abort::LengthMismatch
                    }
                    Ok(_) => Abort::CommandInvalid,
                };
                sdo::abort(at, why)
            }
            Request::Unsupported(at) => sdo::abort(at, Abort::CommandInvalid),
            Request::ClientAbort => return None,
        };
        Some(reply)
    }

    fn sdo_download(
        &mut self,
        at: Address,
        data: [u8; 4],
        size: Option<usize>,
    ) -> Result<(), Abort> {
        let object = objects::lookup(at)?;
        if !object.writable() {
            return Err(Abort::WriteOfReadOnly);
        }
        let ty = object.data_type();
        if size.is_some_and(|n| n != ty.size()) {
            return Err(Abort::LengthMismatch);
        }
        self.write_object(object, ty.decode(data))
    }
}

// The drive state machine acting on the firmware core.
impl Actuator {
    /// A controlword write: decode the command, move the state machine, and (homing) start
    /// a homing on a rising bit 4.
    fn apply_controlword(&mut self, word: u16) {
        let previous = self.canopen.controlword;
        self.canopen.controlword = word;
        let command = cia402::decode(word, previous);
        if command == Command::FaultReset {
            self.fault_reset();
            return;
        }
        match cia402::next(self.canopen.drive, command) {
            Some(DriveState::OperationEnabled) => self.enable_operation(),
            Some(DriveState::QuickStopActive) => self.quick_stop(),
            Some(to) => self.disable_drive(to),
            None => {
                let new_setpoint = word & 0x10 != 0 && previous & 0x10 == 0;
                if new_setpoint
                    && self.canopen.mode == Mode::Homing
                    && self.canopen.drive == DriveState::OperationEnabled
                {
                    self.home();
                }
            }
        }
    }

    /// Into Operation enabled (also back from quick stop): the firmware's enable, holding the
    /// present position, then the selected mode's targets.
    fn enable_operation(&mut self) {
        let mode = self.canopen.mode;
        if self.mode == ModeState::Run {
            // Back from quick stop: restart the loops from rest as a fresh enable does.
            self.stop();
        }
        self.params.set(index::RUN_MODE, f64::from(mode.run_mode()));
        self.enable();
        if self.mode != ModeState::Run {
            // Refused (a latched fault): the tick moves the drive to Fault.
            return;
        }
        self.canopen.drive = DriveState::OperationEnabled;
        self.canopen.target_position_counts = objects::rad_to_counts(self.angle_rad());
        if mode == Mode::Homing {
            self.home();
        }
        self.apply_targets();
    }

    /// Quick stop: brake on the velocity ramp (acc_rad) to standstill and hold zero speed
    /// until the host enables operation again or disables the drive.
    fn quick_stop(&mut self) {
        self.params.set(index::RUN_MODE, 2.0);
        self.params.set(index::SPD_REF, 0.0);
        self.reset_loops();
        self.canopen.drive = DriveState::QuickStopActive;
    }

    /// Into a torque-off state.
    fn disable_drive(&mut self, to: DriveState) {
        if self.mode == ModeState::Run {
            self.stop();
        }
        self.params
            .set(index::RUN_MODE, f64::from(self.canopen.mode.run_mode()));
        self.canopen.drive = to;
    }

    /// Homing as this drive does it: the present position becomes zero (kept, as a type-6
    /// zero is), and the motor holds it.
    fn home(&mut self) {
        self.params.set(index::RUN_MODE, 5.0);
        self.set_zero();
        self.canopen.target_position_counts = 0;
        self.canopen.homed = true;
    }

    /// Into Fault: torque off, 0x603F set, EMCY sent (unless stopped).
    fn enter_fault(&mut self, error_code: u16) {
        self.disable_drive(DriveState::Fault);
        self.canopen.error_code = error_code;
        tracing::warn!(
            motor = self.can_id,
            error_code,
            fault_word = self.fault_word,
            "robstride CANopen: fault"
        );
        self.queue_emcy(error_code);
    }

    /// A rising controlword bit 7 in Fault: the latched bits whose cause is gone clear; when
    /// none is left the drive goes to Switch on disabled and an "error reset" EMCY follows.
    fn fault_reset(&mut self) {
        if self.canopen.drive != DriveState::Fault {
            return;
        }
        self.clear_faults();
        if self.fault_word != 0 {
            self.canopen.error_code = fault_error_code(self.fault_word);
            return;
        }
        self.canopen.watchdog_expired = false;
        self.canopen.error_code = 0;
        self.canopen.drive = DriveState::SwitchOnDisabled;
        self.queue_emcy(0);
    }

    /// EMCY: error code, error register, then the fault word (§9.1 layout) as
    /// manufacturer-specific bytes.
    fn queue_emcy(&mut self, error_code: u16) {
        if self.canopen.nmt == NmtState::Stopped {
            return;
        }
        let [lo, hi] = error_code.to_le_bytes();
        let word = self.fault_word.to_le_bytes();
        let data = [
            lo,
            hi,
            self.error_register(),
            word[0],
            word[1],
            word[2],
            word[3],
            0,
        ];
        let frame = standard(EMCY_BASE + u16::from(self.can_id), &data);
        self.canopen.outbox.extend(frame);
    }
}

/// 0x603F for a fault word: the CiA-402 code of its most telling bit.
fn fault_error_code(word: u32) -> u16 {
    let has = |fault: Fault| word & fault.word_bit() != 0;
    if has(Fault::OverVoltage) {
        0x3210
    } else if has(Fault::UnderVoltage) {
        0x3220
    } else if has(Fault::OverTemperature) {
        0x4310
    } else if has(Fault::StallOverload) {
        0x2310
    } else if word & phase_bits() != 0 {
        0x2300
    } else if has(Fault::GateDriver) {
        0x5400
    } else if has(Fault::EncoderNotCalibrated) {
        0x7300
    } else {
        0x1000
    }
}

fn phase_bits() -> u32 {
    use crate::robstride::faults::Phase;
    [Phase::A, Phase::B, Phase::C]
        .into_iter()
        .map(|phase| Fault::PhaseOverCurrent(phase).word_bit())
        .fold(0, |bits, bit| bits | bit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes_map_onto_the_firmware_run_modes() {
        for (code, run_mode) in [(1, 1), (3, 2), (4, 3), (5, 5), (6, 5)] {
            let mode = Mode::from_code(code).unwrap();
            assert_eq!(i64::from(mode.code()), code);
            assert_eq!(mode.run_mode(), run_mode);
        }
        for code in [0, 2, 7, 8, -1] {
            assert_eq!(Mode::from_code(code), None);
        }
    }

    #[test]
    fn fault_words_give_cia_402_error_codes() {
        assert_eq!(fault_error_code(Fault::OverTemperature.word_bit()), 0x4310);
        assert_eq!(fault_error_code(Fault::UnderVoltage.word_bit()), 0x3220);
        assert_eq!(fault_error_code(Fault::GateDriver.word_bit()), 0x5400);
        assert_eq!(fault_error_code(1 << 8), 0x1000);
    }
}
