//! One emulated actuator: the firmware's state machine, its reply to every communication type,
//! its control loops, thermal and fault models, and the plant it drives.
//!
//! [`Actuator`] is pure and synchronous (frames in, frames out, `tick` per millisecond) so it
//! can be tested without a bus; [`crate::robstride::RobstrideBus`] runs many of them on one.

use std::collections::BTreeMap;

use bus::CanFrame;
use serde::{Deserialize, Serialize};

use crate::robstride::codec::{self, CommType, ExtId};
use crate::robstride::control::{
    OpCommand, Profile, SpeedEnvelope, SpeedLoop, ZERO_MODE_SPEED_RAD_S,
};
use crate::robstride::faults::{self, Fault, Phase, WARNING_OVER_TEMP};
use crate::robstride::host_params;
use crate::robstride::model::{Model, ModelSpec, RangeTable, Ranges};
use crate::robstride::params::{self, index, Access, ParamStore};
use crate::robstride::rig::{Load, Plant, RigPlant, WorldPlant};
use crate::state_file::InvalidField;

mod canopen;
mod host;
mod mit;

/// Host ID the manuals use and the motor assumes until a host speaks.
pub const DEFAULT_HOST_ID: u8 = 0xFD;
/// Destination byte of type-0 replies ("broadcast" marker).
const TYPE0_DST: u8 = 0xFE;
/// Inner control-loop substeps per 1 ms tick (10 kHz, as the firmware's loops run faster than
/// the host's 1 kHz).
const SUBSTEPS: u32 = 10;
/// The highest CAN ID the parameter table allows (0x200a max 127).
const MAX_CAN_ID: u8 = 0x7F;

/// Mode state in bits 23..22 of status frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ModeState {
    /// Torque off (power-on, after stop, fault or CAN timeout).
    Reset,
    /// Encoder calibration (or waiting for it).
    Calibration,
    /// Running (after enable).
    Run,
}

impl ModeState {
    fn bits(self) -> u16 {
        match self {
            ModeState::Reset => 0,
            ModeState::Calibration => 1,
            ModeState::Run => 2,
        }
    }
}

/// Which comm type active reports use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum ReportType {
    /// Type 24 (current firmware).
    #[default]
    Type24,
    /// Type 2 (firmware before RS00 0.0.3.3, RS03 0.3.1.3, …).
    Type2,
}

/// Configuration of one emulated actuator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotorConfig {
    /// CAN ID at first power-on (1..=127); a state file may hold a newer one.
    pub can_id: u8,
    /// Model.
    pub model: Model,
    /// What the motor drives.
    pub load: Load,
    /// Which scaling table the firmware uses.
    pub range_table: RangeTable,
    /// Explicit ranges, overriding the table (a per-model setting).
    pub ranges: Option<Ranges>,
    /// MCU unique ID; derived from the model and first CAN ID when `None` (stable).
    pub uid: Option<[u8; 8]>,
    /// Viscous friction of the rig (N·m·s/rad).
    pub friction_nm_s_per_rad: f64,
    /// Shaft angle at start (rad, 0 = pendulum hanging down).
    pub start_angle_rad: f64,
    /// Comm type of active reports.
    pub report_type: ReportType,
    /// Ambient temperature (°C).
    pub ambient_c: f64,
    /// Winding thermal time constant (s).
    pub thermal_time_constant_s: f64,
    /// Steady-state winding temperature rise at rated current (°C).
    pub thermal_rise_at_rated_c: f64,
    /// canTimeout ticks per second (manual: 20000, i.e. 50 µs ticks).
    pub can_timeout_ticks_per_s: f64,
    /// How long peak current may flow before the I²t overload trips (s).
    pub overload_time_at_peak_s: f64,
    /// Which integrator moves the rig.
    pub plant: PlantKind,
}

/// Which integrator moves the rig.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum PlantKind {
    /// The one-joint rig integrated directly (fast; default).
    #[default]
    Analytic,
    /// The rig's URDF in the rapier3d physics world ([`crate::physics::ArmWorld`]).
    World,
}

impl MotorConfig {
    /// A motor with default rig (1 kg, 0.1 m disc) and manual ranges.
    pub fn new(can_id: u8, model: Model) -> Self {
        Self {
            can_id,
            model,
            load: Load::default(),
            range_table: RangeTable::Manual,
            ranges: None,
            uid: None,
            friction_nm_s_per_rad: 0.0,
            start_angle_rad: 0.0,
            report_type: ReportType::Type24,
            ambient_c: 25.0,
            thermal_time_constant_s: 60.0,
            thermal_rise_at_rated_c: 60.0,
            can_timeout_ticks_per_s: 20_000.0,
            overload_time_at_peak_s: 2.0,
            plant: PlantKind::Analytic,
        }
    }

    /// The same motor with another load.
    pub fn with_load(mut self, load: Load) -> Self {
        self.load = load;
        self
    }

    /// The UID this motor reports: the configured one, or one derived from model and first ID.
    pub fn effective_uid(&self) -> [u8; 8] {
        self.uid.unwrap_or_else(|| {
            // FNV-1a over (model, first id): stable across runs, distinct per motor.
            let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
            for byte in self.model.name().bytes().chain([self.can_id]) {
                hash ^= u64::from(byte);
                hash = hash.wrapping_mul(0x0000_0100_0000_01B3);
            }
            hash.to_le_bytes()
        })
    }
}

/// What survives an emulator restart (written to the state file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PersistedMotor {
    /// CAN ID (type 7 takes effect at once and is kept).
    pub can_id: u8,
    /// Host ID replies go to.
    pub master_id: u8,
    /// Mechanical zero: plant angle that reads 0 (rad).
    pub zero_offset_rad: f64,
    /// Saved parameters (type 22), by index.
    pub params: BTreeMap<u16, f64>,
    /// Baud code for the next power-on (1 = 1M, 2 = 500k, 3 = 250k, 4 = 125k).
    pub baud_code: u8,
    /// Protocol for the next power-on (0 private, 1 CANopen, 2 MIT).
    pub protocol: u8,
}

impl PersistedMotor {
    /// Check every value with the rules the commands that store it apply (type 7 for the
    /// CAN ID, 22/23/25 for baud and protocol, any command for the host ID). Saved parameters
    /// are applied at power-on as a type-18 write would apply them (clamped to their range).
    /// The error names the field under `prefix` (`motors.<uid>`).
    pub fn validate(&self, prefix: &str) -> Result<(), InvalidField> {
        let refuse = |field: &str, problem: String| {
            Err(InvalidField::new(format!("{prefix}.{field}"), problem))
        };
        if !can_id_accepted(self.can_id) {
            return refuse(
                "can_id",
                format!("{} is outside 1..={MAX_CAN_ID}", self.can_id),
            );
        }
        if !host_id_accepted(self.master_id) {
            return refuse("master_id", "0 is not a host ID".to_owned());
        }
        if baud_code_bps(self.baud_code).is_none() {
            return refuse(
                "baud_code",
                format!("{} is not a baud code (1–4)", self.baud_code),
            );
        }
        if !protocol_accepted(self.protocol) {
            return refuse(
                "protocol",
                format!("{} is not a protocol (0–2)", self.protocol),
            );
        }
        if !self.zero_offset_rad.is_finite() {
            return refuse("zero_offset_rad", "not a finite angle".to_owned());
        }
        Ok(())
    }
}

/// A point-in-time view of one actuator for the harness.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotorSnapshot {
    /// Current CAN ID.
    pub can_id: u8,
    /// Model.
    pub model: Model,
    /// Mode state.
    pub mode: ModeState,
    /// run_mode (0..5).
    pub run_mode: u8,
    /// Reported angle (rad, after the mechanical zero, not wrapped).
    pub angle_rad: f64,
    /// Speed (rad/s).
    pub speed_rad_s: f64,
    /// Torque the motor produces (N·m).
    pub torque_nm: f64,
    /// iq (A).
    pub iq_a: f64,
    /// Winding temperature (°C).
    pub temperature_c: f64,
    /// Supply voltage (V).
    pub bus_voltage_v: f64,
    /// Latched fault word (type-21 layout).
    pub fault_word: u32,
    /// Warning word (type-21 layout).
    pub warning_word: u32,
    /// Active reporting on.
    pub active_report: bool,
    /// Host ID replies go to.
    pub master_id: u8,
    /// Baud code in effect (1 = 1 Mbit/s …).
    pub baud_code: u8,
    /// Protocol in effect (0 private, 1 CANopen, 2 MIT).
    pub protocol: u8,
    /// False when a baud or protocol switch made the motor deaf to this bus.
    pub listening: bool,
}

fn make_plant(config: &MotorConfig, spec: &ModelSpec) -> Box<dyn Plant> {
    let analytic = || {
        Box::new(RigPlant::new(
            config.load,
            spec.rotor_inertia_kg_m2,
            config.friction_nm_s_per_rad,
            config.start_angle_rad,
        ))
    };
    match config.plant {
        PlantKind::Analytic => analytic(),
        PlantKind::World => match WorldPlant::new(
            config.load,
            spec.rotor_inertia_kg_m2,
            config.friction_nm_s_per_rad,
            config.start_angle_rad,
            1e-3 / f64::from(SUBSTEPS),
        ) {
            Ok(world) => Box::new(world),
            Err(error) => {
                // The rig URDF is generated by us; a failure is a bug, not user input, but the
                // emulator still runs on the analytic rig rather than dying.
                tracing::error!(%error, "robstride: rig world failed to load, using the analytic rig");
                analytic()
            }
        },
    }
}

/// Whether a type-7 command may give a motor this CAN ID (0 and above 127 are invalid).
fn can_id_accepted(can_id: u8) -> bool {
    (1..=MAX_CAN_ID).contains(&can_id)
}

/// Whether a type-25 command may select this protocol (0 private, 1 CANopen, 2 MIT).
fn protocol_accepted(protocol: u8) -> bool {
    protocol <= 2
}

/// Whether a host ID is one replies can go to (0 would make them unaddressable).
fn host_id_accepted(host: u8) -> bool {
    host != 0
}

/// Baud code → bit rate.
pub fn baud_code_bps(code: u8) -> Option<u32> {
    match code {
        1 => Some(1_000_000),
        2 => Some(500_000),
        3 => Some(250_000),
        4 => Some(125_000),
        _ => None,
    }
}

/// One emulated actuator.
pub struct Actuator {
    config: MotorConfig,
    ranges: Ranges,
    spec: ModelSpec,
    uid: [u8; 8],
    can_id: u8,
    master_id: u8,
    mode: ModeState,
    params: ParamStore,
    fault_word: u32,
    warning_word: u32,
    encoder_uncalibrated: bool,
    calibration_left_ms: u32,
    op: OpCommand,
    profile: Profile,
    speed_ramp_rad_s: f64,
    speed_loop: SpeedLoop,
    plant: Box<dyn Plant>,
    zero_offset_rad: f64,
    iq_a: f64,
    torque_nm: f64,
    temperature_c: f64,
    bus_voltage_v: f64,
    overload_a2s: f64,
    active_report: bool,
    report_elapsed_ms: u32,
    since_command_s: f64,
    baud_code: u8,
    pending_baud: u8,
    protocol: u8,
    pending_protocol: u8,
    listening: bool,
    persist_requested: bool,
    saved_params: BTreeMap<u16, f64>,
    /// NMT, drive state and targets while speaking CANopen (protocol 1).
    canopen: canopen::CanopenNode,
}

impl Actuator {
    /// Power on a motor, restoring `persisted` state (from a state file) if any.
    pub fn new(
        config: MotorConfig,
        persisted: Option<&PersistedMotor>,
        bus_bitrate_bps: u32,
    ) -> Self {
        let ranges = config
            .ranges
            .unwrap_or_else(|| config.model.ranges(config.range_table));
        let spec = config.model.spec();
        let mut params = ParamStore::new(config.model, &ranges);
        let plant = make_plant(&config, &spec);
        let saved_params = persisted
            .map(|saved| saved.params.clone())
            .unwrap_or_default();
        let (can_id, master_id, zero, baud, protocol) = match persisted {
            Some(saved) => {
                for (index, value) in &saved.params {
                    params.set(*index, *value);
                }
                (
                    saved.can_id,
                    saved.master_id,
                    saved.zero_offset_rad,
                    saved.baud_code,
                    saved.protocol,
                )
            }
            None => (config.can_id, DEFAULT_HOST_ID, 0.0, 1, 0),
        };
        // A node at another bit rate cannot decode the bus.
        let listening = baud_code_bps(baud) == Some(bus_bitrate_bps)
            && (protocol == 0
                || protocol == canopen::PROTOCOL_CANOPEN
                || protocol == mit::PROTOCOL_MIT);
        Self {
            uid: config.effective_uid(),
            temperature_c: config.ambient_c,
            bus_voltage_v: spec.nominal_voltage_v,
            config,
            ranges,
            spec,
            can_id,
            master_id,
            mode: ModeState::Reset,
            params,
            fault_word: 0,
            warning_word: 0,
            encoder_uncalibrated: false,
            calibration_left_ms: 0,
            op: OpCommand::default(),
            profile: Profile::default(),
            speed_ramp_rad_s: 0.0,
            speed_loop: SpeedLoop::default(),
            plant,
            zero_offset_rad: zero,
            iq_a: 0.0,
            torque_nm: 0.0,
            overload_a2s: 0.0,
            active_report: false,
            report_elapsed_ms: 0,
            since_command_s: 0.0,
            baud_code: baud,
            pending_baud: baud,
            protocol,
            pending_protocol: protocol,
            listening,
            persist_requested: false,
            saved_params,
            canopen: canopen::CanopenNode::new(),
        }
    }

    /// Current CAN ID.
    pub fn can_id(&self) -> u8 {
        self.can_id
    }

    /// Set the host ID replies go to until a host speaks (power-on setting).
    pub fn set_master_id(&mut self, host_id: u8) {
        self.master_id = host_id;
    }

    /// The configuration it was built from.
    pub fn config(&self) -> &MotorConfig {
        &self.config
    }

    /// The scaling ranges in use.
    pub fn ranges(&self) -> &Ranges {
        &self.ranges
    }

    /// The MCU UID.
    pub fn uid(&self) -> [u8; 8] {
        self.uid
    }

    /// True once since the last call if something persistent changed (the caller writes the
    /// state file).
    pub fn take_persist_request(&mut self) -> bool {
        std::mem::take(&mut self.persist_requested)
    }

    /// The state to write to the state file.
    pub fn persisted(&self) -> PersistedMotor {
        PersistedMotor {
            can_id: self.can_id,
            master_id: self.master_id,
            zero_offset_rad: self.zero_offset_rad,
            params: self.saved_params.clone(),
            baud_code: self.pending_baud,
            protocol: self.pending_protocol,
        }
    }
}

// Frame handling: one method per communication type.
impl Actuator {
    /// React to a frame from the bus; returns the frames the motor sends in reply.
    pub fn handle_frame(&mut self, frame: &CanFrame) -> Vec<CanFrame> {
        let mut out = Vec::new();
        if self.listening && self.protocol == canopen::PROTOCOL_CANOPEN {
            return self.handle_canopen_frame(frame);
        }
        if self.listening && self.protocol == mit::PROTOCOL_MIT {
            return self.handle_mit_frame(frame);
        }
        if !self.listening || !frame.is_extended() {
            return out;
        }
        let id = ExtId::parse(frame.raw_id());
        if id.dst != self.can_id {
            return out;
        }
        let data = codec::payload8(frame);
        self.since_command_s = 0.0;
        let host = id.low_data2();
        match id.comm {
            CommType::GetId => {
                self.note_host(host);
                out.extend(self.type0_reply());
            }
            CommType::OpControl => {
                self.op = self.decode_op(id.data2, &data);
                out.extend(self.status_frame(CommType::Status));
            }
            CommType::Status => {
                out.extend(self.status_frame(CommType::Status));
            }
            CommType::Enable => {
                self.note_host(host);
                self.enable();
                out.extend(self.status_frame(CommType::Status));
            }
            CommType::Stop => {
                self.note_host(host);
                self.stop();
                if data[0] == 0 && data[1] == 0xC4 {
                    out.extend(self.version_reply());
                } else {
                    if data[0] == 1 {
                        self.clear_faults();
                    }
                    out.extend(self.status_frame(CommType::Status));
                }
            }
            CommType::Calibrate => {
                self.note_host(host);
                if self.mode != ModeState::Run {
                    self.mode = ModeState::Calibration;
                    self.calibration_left_ms = 1000;
                }
                out.extend(self.status_frame(CommType::Status));
            }
            CommType::SetZero => {
                self.note_host(host);
                if data[0] == 1 {
                    self.set_zero();
                }
                out.extend(self.status_frame(CommType::Status));
            }
            CommType::SetCanId => {
                self.note_host(host);
                let new_id = id.high_data2();
                // Refused while enabled (no reply), as hosts report; 0 and >127 are invalid.
                if self.mode != ModeState::Run && can_id_accepted(new_id) {
                    tracing::info!(old = self.can_id, new = new_id, "robstride: CAN ID changed");
                    self.can_id = new_id;
                    self.persist_requested = true;
                    out.extend(self.type0_reply());
                }
            }
            CommType::ReadParam => {
                self.note_host(host);
                out.extend(self.read_param(u16::from_le_bytes([data[0], data[1]])));
            }
            CommType::WriteParam => {
                self.note_host(host);
                let value = [data[4], data[5], data[6], data[7]];
                out.extend(self.write_param(u16::from_le_bytes([data[0], data[1]]), value));
            }
            CommType::Save => {
                self.note_host(host);
                if data == [1, 2, 3, 4, 5, 6, 7, 8] {
                    self.saved_params = self.params.saved_values();
                    self.persist_requested = true;
                    out.extend(self.status_frame(CommType::Status));
                }
            }
            CommType::Baud => {
                self.note_host(host);
                if codec::has_magic_prefix(&data) && baud_code_bps(data[6]).is_some() {
                    self.pending_baud = data[6];
                    self.persist_requested = true;
                    out.extend(self.type0_reply());
                }
            }
            CommType::ActiveReport => {
                self.note_host(host);
                if codec::has_magic_prefix(&data) && data[6] <= 1 {
                    self.active_report = data[6] == 1;
                    self.report_elapsed_ms = 0;
                }
            }
            CommType::Protocol => {
                self.note_host(host);
                if codec::has_magic_prefix(&data) && protocol_accepted(data[6]) {
                    self.pending_protocol = data[6];
                    self.persist_requested = true;
                    out.extend(self.type0_reply());
                }
            }
            CommType::Fault | CommType::Unknown(_) => {}
        }
        out
    }

    fn note_host(&mut self, host: u8) {
        // Host ID 0 would make replies unaddressable; keep the last real one.
        if host_id_accepted(host) && host != self.can_id {
            self.master_id = host;
        }
    }

    fn decode_op(&self, data2: u16, data: &[u8; 8]) -> OpCommand {
        let r = &self.ranges;
        let f = |raw: u16, min: f32, max: f32| f64::from(codec::u16_to_float(raw, min, max));
        OpCommand {
            angle_rad: f(codec::be_u16(data, 0), -r.angle_rad, r.angle_rad),
            speed_rad_s: f(codec::be_u16(data, 2), -r.speed_rad_s, r.speed_rad_s),
            kp: f(codec::be_u16(data, 4), 0.0, r.kp_max),
            kd: f(codec::be_u16(data, 6), 0.0, r.kd_max),
            torque_nm: f(data2, -r.torque_nm, r.torque_nm),
        }
    }

    fn enable(&mut self) {
        if self.fault_word != 0 || self.encoder_uncalibrated || self.mode == ModeState::Calibration
        {
            tracing::debug!(
                motor = self.can_id,
                faults = self.fault_word,
                "robstride: enable refused"
            );
            return;
        }
        if self.mode == ModeState::Run {
            return;
        }
        self.mode = ModeState::Run;
        self.reset_loops();
        // Hold where we are: position targets start at the current angle so enabling never
        // makes the joint jump toward a stale target.
        let angle = self.angle_rad();
        self.params.set(index::LOC_REF, angle);
        self.profile = Profile::at_rest(angle);
    }

    fn stop(&mut self) {
        self.mode = if self.encoder_uncalibrated {
            ModeState::Calibration
        } else {
            ModeState::Reset
        };
        self.reset_loops();
    }

    fn reset_loops(&mut self) {
        self.speed_loop = SpeedLoop::default();
        self.speed_ramp_rad_s = self.plant.velocity_rad_s();
        self.iq_a = 0.0;
        self.torque_nm = 0.0;
    }

    /// Clear latched faults whose cause is gone (type 4 with byte0 = 1).
    fn clear_faults(&mut self) {
        let mut still = 0;
        if self.temperature_c >= self.spec.over_temp_fault_c {
            still |= Fault::OverTemperature.word_bit();
        }
        if self.bus_voltage_v < self.spec.under_voltage_v {
            still |= Fault::UnderVoltage.word_bit();
        }
        if self.bus_voltage_v > self.spec.over_voltage_v {
            still |= Fault::OverVoltage.word_bit();
        }
        if self.encoder_uncalibrated {
            still |= Fault::EncoderNotCalibrated.word_bit();
        }
        self.fault_word &= still;
        self.overload_a2s = 0.0;
    }

    fn set_zero(&mut self) {
        // Newer firmware ignores zeroing in PP mode (spec §5.6).
        if self.run_mode() == 1 {
            return;
        }
        self.zero_offset_rad = self.plant.position_rad();
        // The internal targets move with the zero so the joint does not jump.
        self.params.set(index::LOC_REF, 0.0);
        self.op.angle_rad = 0.0;
        self.profile = Profile::at_rest(0.0);
        self.persist_requested = true;
    }

    fn read_param(&self, idx: u16) -> Option<CanFrame> {
        // 0x70xx and the host tables (0x20xx/0x30xx); see `host.rs`.
        let Some(bytes) = self.param_bytes(idx) else {
            // Failure echo as captured on hardware: status 1, zero payload.
            return codec::frame(
                CommType::ReadParam,
                self.reply_data2(1),
                self.master_id,
                [0; 8],
            );
        };
        let [lo, hi] = idx.to_le_bytes();
        let data = [lo, hi, 0, 0, bytes[0], bytes[1], bytes[2], bytes[3]];
        codec::frame(
            CommType::ReadParam,
            self.reply_data2(0),
            self.master_id,
            data,
        )
    }

    fn write_param(&mut self, idx: u16, bytes: [u8; 4]) -> Option<CanFrame> {
        if let Some(row) = host_params::lookup(self.config.model, idx) {
            return self.write_host_param(row, bytes);
        }
        let spec = self.params.spec(idx).copied();
        // Not documented for writes: the type-17 failure flag with the index echoed.
        let refusal = || self.write_refusal(idx);
        let Some(spec) = spec.filter(|spec| spec.access == Access::ReadWrite) else {
            return refusal();
        };
        let Some(value) = params::decode_value(spec.ty, bytes) else {
            return refusal();
        };
        if idx == index::RUN_MODE && self.mode == ModeState::Run {
            // Mode changes only while stopped: ignored, still acknowledged (spec §17 choice).
            tracing::debug!(
                motor = self.can_id,
                "robstride: run_mode write ignored while running"
            );
            return self.status_frame(CommType::Status);
        }
        let old_mode = self.run_mode();
        if let Some(stored) = self.params.set(idx, value) {
            match idx {
                index::RUN_MODE if self.run_mode() != old_mode => self.reset_loops(),
                index::LOC_REF => self.profile.target_rad = stored,
                _ => {}
            }
        }
        self.status_frame(CommType::Status)
    }

    fn reply_data2(&self, status: u8) -> u16 {
        (u16::from(status) << 8) | u16::from(self.can_id)
    }

    fn type0_reply(&self) -> Option<CanFrame> {
        codec::frame(CommType::GetId, u16::from(self.can_id), TYPE0_DST, self.uid)
    }

    fn status_data2(&self) -> u16 {
        let faults = u16::from(faults::status_bits(self.fault_word) & 0x3F);
        (self.mode.bits() << 14) | (faults << 8) | u16::from(self.can_id)
    }

    fn status_frame(&self, comm: CommType) -> Option<CanFrame> {
        let data = codec::status_payload(
            wrap_angle(self.angle_rad(), f64::from(self.ranges.angle_rad)) as f32,
            self.plant.velocity_rad_s() as f32,
            self.torque_nm as f32,
            self.temperature_c as f32,
            &self.ranges,
        );
        codec::frame(comm, self.status_data2(), self.master_id, data)
    }

    fn version_reply(&self) -> Option<CanFrame> {
        let v = self.spec.firmware_version;
        let data = [0x00, 0xC4, 0x56, v[0], v[1], v[2], v[3], 0x00];
        codec::frame(CommType::Status, self.status_data2(), self.master_id, data)
    }

    fn fault_frame(&self) -> Option<CanFrame> {
        let mut data = [0u8; 8];
        data[..4].copy_from_slice(&self.fault_word.to_le_bytes());
        data[4..].copy_from_slice(&self.warning_word.to_le_bytes());
        codec::frame(
            CommType::Fault,
            u16::from(self.can_id),
            self.master_id,
            data,
        )
    }

    fn run_mode(&self) -> u8 {
        self.params.get(index::RUN_MODE) as u8
    }

    fn angle_rad(&self) -> f64 {
        self.plant.position_rad() - self.zero_offset_rad
    }
}

/// Wrap into [−range, range) the way type-2 angles are periodic (spec §3.3).
fn wrap_angle(angle: f64, range: f64) -> f64 {
    if angle >= -range && angle < range {
        return angle;
    }
    (angle + range).rem_euclid(2.0 * range) - range
}

// Time: physics, loops, thermal model, watchdog, reporting.
impl Actuator {
    /// Advance 1 ms: control loops and plant (10 substeps), thermal and overload models, the
    /// CAN watchdog and active reporting. Returns frames the motor sends on its own.
    pub fn tick(&mut self) -> Vec<CanFrame> {
        let mut out = Vec::new();
        if self.calibration_left_ms > 0 {
            self.calibration_left_ms -= 1;
            if self.calibration_left_ms == 0 {
                self.encoder_uncalibrated = false;
                self.fault_word &= !Fault::EncoderNotCalibrated.word_bit();
                self.mode = ModeState::Reset;
            }
        }
        let dt = 1e-3 / f64::from(SUBSTEPS);
        for _ in 0..SUBSTEPS {
            let torque = self.control(dt);
            self.plant.step(torque, dt);
        }
        self.update_thermal(1e-3);
        self.update_overload(1e-3);
        self.watchdog(1e-3);
        out.extend(self.check_conditions());
        if self.active_report && self.listening {
            self.report_elapsed_ms += 1;
            let n = self.params.get(index::EPSCAN_TIME).max(1.0);
            let period_ms = (10.0 + 5.0 * (n - 1.0)) as u32;
            if self.report_elapsed_ms >= period_ms {
                self.report_elapsed_ms = 0;
                let comm = match self.config.report_type {
                    ReportType::Type24 => CommType::ActiveReport,
                    ReportType::Type2 => CommType::Status,
                };
                if self.protocol == mit::PROTOCOL_MIT {
                    // MIT command 13: reports are Response 1 frames.
                    out.extend(self.mit_status());
                } else {
                    out.extend(self.status_frame(comm));
                }
            }
        }
        if self.listening && self.protocol == canopen::PROTOCOL_CANOPEN {
            out.extend(self.canopen_tick());
        }
        out
    }

    /// The torque–speed line at the present supply voltage (no-load speed ∝ voltage).
    fn envelope(&self, dt: f64) -> SpeedEnvelope {
        let volts = self.bus_voltage_v.max(0.0) / self.spec.nominal_voltage_v;
        SpeedEnvelope {
            peak_torque_nm: self.spec.peak_torque_nm,
            no_load_speed_rad_s: self.spec.no_load_speed_rad_s * volts,
            inertia_kg_m2: self.plant.inertia_kg_m2(),
            dt_s: dt,
        }
    }

    fn control(&mut self, dt: f64) -> f64 {
        if self.mode != ModeState::Run || self.fault_word != 0 {
            self.iq_a = 0.0;
            self.torque_nm = 0.0;
            // De-energised, the drive shorts the windings against back-driving unless the
            // model has 0x702A `damper` and it is set to 1. That torque is passive: the
            // reported torque and current stay those the drive commands (0). The manual has a
            // changed `damper` take effect after save and power cycle; we apply it at once.
            let damper_off = self.spec.has_damper_param && self.params.get(index::DAMPER) >= 0.5;
            if damper_off {
                return 0.0;
            }
            return self
                .envelope(dt)
                .short_circuit_brake(self.plant.velocity_rad_s());
        }
        let kt = self.spec.torque_constant_nm_per_a;
        let angle = self.angle_rad();
        let speed = self.plant.velocity_rad_s();
        let inertia = self.plant.inertia_kg_m2();
        // Gains above what an explicit step at `dt` can hold stable for this inertia would
        // make the simulation explode where the real loop (with its own filters) does not.
        let kd_cap = 0.5 * inertia / dt;
        let kp_cap = 0.25 * inertia / (dt * dt);
        let speed_kp = self.params.get(index::SPD_KP).min(kd_cap / kt);
        let speed_ki = self.params.get(index::SPD_KI);
        let limit_cur = self.params.get(index::LIMIT_CUR);
        let loc_kp = self.params.get(index::LOC_KP);
        let torque_cmd = match self.run_mode() {
            0 => {
                let op = self.op;
                let torque = op.kp.min(kp_cap) * (op.angle_rad - angle)
                    + op.kd.min(kd_cap) * (op.speed_rad_s - speed)
                    + op.torque_nm;
                self.iq_a = torque / kt;
                torque
            }
            1 => {
                let vel_max = self.params.get(index::VEL_MAX);
                let acc = self.params.get(index::ACC_SET);
                let dcc = self.params.get(index::DCC_SET);
                self.profile.step(vel_max, acc, dcc, dt);
                let target = self.profile.speed_rad_s + loc_kp * (self.profile.angle_rad - angle);
                let iq = self
                    .speed_loop
                    .update(target - speed, speed_kp, speed_ki, limit_cur, dt);
                self.iq_a = iq;
                iq * kt
            }
            2 => {
                let reference = self.params.get(index::SPD_REF);
                let acc = self.params.get(index::ACC_RAD).max(0.0) * dt;
                self.speed_ramp_rad_s += (reference - self.speed_ramp_rad_s).clamp(-acc, acc);
                let error = self.speed_ramp_rad_s - speed;
                let iq = self
                    .speed_loop
                    .update(error, speed_kp, speed_ki, limit_cur, dt);
                self.iq_a = iq;
                iq * kt
            }
            3 => {
                let limit = f64::from(self.ranges.current_a);
                self.iq_a = self.params.get(index::IQ_REF).clamp(-limit, limit);
                self.iq_a * kt
            }
            4 => {
                let target = (loc_kp * -angle).clamp(-ZERO_MODE_SPEED_RAD_S, ZERO_MODE_SPEED_RAD_S);
                let iq = self
                    .speed_loop
                    .update(target - speed, speed_kp, speed_ki, limit_cur, dt);
                self.iq_a = iq;
                iq * kt
            }
            _ => {
                let limit_spd = self.params.get(index::LIMIT_SPD);
                let loc_ref = self.params.get(index::LOC_REF);
                let target = (loc_kp * (loc_ref - angle)).clamp(-limit_spd, limit_spd);
                let iq = self
                    .speed_loop
                    .update(target - speed, speed_kp, speed_ki, limit_cur, dt);
                self.iq_a = iq;
                iq * kt
            }
        };
        let limit = self
            .params
            .get(index::LIMIT_TORQUE)
            .min(f64::from(self.ranges.torque_nm));
        let torque = torque_cmd.clamp(-limit, limit);
        self.torque_nm = self.envelope(dt).limit(torque, speed);
        if self.torque_nm != torque_cmd {
            self.iq_a = self.torque_nm / kt;
        }
        self.torque_nm
    }

    fn update_thermal(&mut self, dt: f64) {
        let ratio = self.iq_a / self.spec.rated_current_a;
        let target = self.config.ambient_c + self.config.thermal_rise_at_rated_c * ratio * ratio;
        let tau = self.config.thermal_time_constant_s.max(1e-3);
        self.temperature_c += (target - self.temperature_c) * (dt / tau).min(1.0);
    }

    fn update_overload(&mut self, dt: f64) {
        let rated2 = self.spec.rated_current_a.powi(2);
        self.overload_a2s = (self.overload_a2s + (self.iq_a.powi(2) - rated2) * dt).max(0.0);
    }

    fn watchdog(&mut self, dt: f64) {
        self.since_command_s += dt;
        let ticks = self.params.get(index::CAN_TIMEOUT);
        if ticks <= 0.0 || self.mode != ModeState::Run {
            return;
        }
        let window_s = ticks / self.config.can_timeout_ticks_per_s.max(1.0);
        if self.since_command_s > window_s {
            tracing::info!(
                motor = self.can_id,
                window_s,
                "robstride: CAN timeout, motor reset"
            );
            self.stop();
        }
    }

    /// Latch faults whose conditions hold, raise the warning, and send a type-21 frame on
    /// every change of the fault or warning word.
    fn check_conditions(&mut self) -> Option<CanFrame> {
        let before = (self.fault_word, self.warning_word);
        if self.temperature_c >= self.spec.over_temp_fault_c {
            self.fault_word |= Fault::OverTemperature.word_bit();
        }
        if self.temperature_c >= self.spec.over_temp_warning_c {
            self.warning_word |= WARNING_OVER_TEMP;
        } else if self.temperature_c < self.spec.over_temp_warning_c - 5.0 {
            self.warning_word &= !WARNING_OVER_TEMP;
        }
        if self.bus_voltage_v < self.spec.under_voltage_v {
            self.fault_word |= Fault::UnderVoltage.word_bit();
        }
        if self.bus_voltage_v > self.spec.over_voltage_v {
            self.fault_word |= Fault::OverVoltage.word_bit();
        }
        let budget = (self.spec.peak_current_a.powi(2) - self.spec.rated_current_a.powi(2))
            * self.config.overload_time_at_peak_s;
        if self.overload_a2s > budget {
            self.fault_word |= Fault::StallOverload.word_bit();
            self.overload_a2s = 0.0;
        }
        if self.encoder_uncalibrated {
            self.fault_word |= Fault::EncoderNotCalibrated.word_bit();
        }
        self.after_fault_change(before)
    }

    fn after_fault_change(&mut self, before: (u32, u32)) -> Option<CanFrame> {
        if (self.fault_word, self.warning_word) == before {
            return None;
        }
        if self.fault_word & !before.0 != 0 {
            tracing::warn!(
                motor = self.can_id,
                fault_word = self.fault_word,
                "robstride: fault"
            );
            self.stop();
        }
        // Type 21 is a private-protocol frame; the MIT variant shows faults in its replies and
        // a CANopen node sends EMCY (see `canopen`).
        if self.listening && self.protocol == 0 {
            self.fault_frame()
        } else {
            None
        }
    }
}

// The harness's side door: faults, supply, temperature, snapshot.
impl Actuator {
    /// Inject a fault: set its physical cause (heat, supply) or latch a one-shot event.
    /// Returns the type-21 frame the motor sends.
    pub fn inject(&mut self, fault: Fault) -> Option<CanFrame> {
        let before = (self.fault_word, self.warning_word);
        match fault {
            Fault::OverTemperature => {
                self.temperature_c = self.spec.over_temp_fault_c + 5.0;
                self.warning_word |= WARNING_OVER_TEMP;
            }
            Fault::UnderVoltage => self.bus_voltage_v = self.spec.under_voltage_v - 2.0,
            Fault::OverVoltage => self.bus_voltage_v = self.spec.over_voltage_v + 2.0,
            Fault::EncoderNotCalibrated => {
                self.encoder_uncalibrated = true;
                self.mode = ModeState::Calibration;
            }
            Fault::PhaseOverCurrent(_) | Fault::StallOverload | Fault::GateDriver => {}
        }
        self.fault_word |= fault.word_bit();
        self.after_fault_change(before)
    }

    /// Remove a fault's cause (cool down, restore the supply, calibrate). The latched bit stays
    /// until the host sends stop + clear, as on hardware.
    pub fn remove_cause(&mut self, fault: Fault) {
        match fault {
            Fault::OverTemperature => self.temperature_c = self.config.ambient_c,
            Fault::UnderVoltage | Fault::OverVoltage => {
                self.bus_voltage_v = self.spec.nominal_voltage_v
            }
            Fault::EncoderNotCalibrated => {
                self.encoder_uncalibrated = false;
                if self.mode == ModeState::Calibration {
                    self.mode = ModeState::Reset;
                }
            }
            Fault::PhaseOverCurrent(Phase::A | Phase::B | Phase::C)
            | Fault::StallOverload
            | Fault::GateDriver => {}
        }
    }

    /// Set the supply voltage (V); faults latch on the next tick if it is out of range.
    pub fn set_bus_voltage(&mut self, volts: f64) {
        if volts.is_finite() {
            self.bus_voltage_v = volts;
        }
    }

    /// Set the winding temperature (°C).
    pub fn set_temperature(&mut self, celsius: f64) {
        if celsius.is_finite() {
            self.temperature_c = celsius;
        }
    }

    /// Push the load with an external torque (N·m).
    pub fn set_external_torque(&mut self, torque_nm: f64) {
        self.plant.set_external_torque_nm(torque_nm);
    }

    /// A view of the motor's state.
    pub fn snapshot(&self) -> MotorSnapshot {
        MotorSnapshot {
            can_id: self.can_id,
            model: self.config.model,
            mode: self.mode,
            run_mode: self.run_mode(),
            angle_rad: self.angle_rad(),
            speed_rad_s: self.plant.velocity_rad_s(),
            torque_nm: self.torque_nm,
            iq_a: self.iq_a,
            temperature_c: self.temperature_c,
            bus_voltage_v: self.bus_voltage_v,
            fault_word: self.fault_word,
            warning_word: self.warning_word,
            active_report: self.active_report,
            master_id: self.master_id,
            baud_code: self.baud_code,
            protocol: self.protocol,
            listening: self.listening,
        }
    }
}
