//! The motor handles against a scripted responder on the virtual bus. The responder replays
//! `fixtures/damiao/`: a request that is byte for byte a host-to-motor vector gets the reply
//! that vector names (its `<name>_reply` for registers, a feedback vector for commands,
//! nothing for `reply=none`), with CTRL_MODE deciding which mode's commands it answers. A
//! request that is no vector goes unanswered, so a wrong byte in the driver ends in a timeout.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use bus::virtual_bus::{VirtualBus, VirtualBusConfig, VirtualNode};
use bus::{CanBus, CanFrame};
use driver::damiao::{
    ControlMode, DamiaoDriver, DamiaoError, DamiaoMotor, DriverConfig, Model, MotorState, Register,
    RegisterValue, VelocityLen,
};
use testkit::fixtures::Vector;

use super::{f, int, text, vectors};

/// What the responder answers a request with.
#[derive(Clone)]
struct Script {
    all: Arc<BTreeMap<String, Vector>>,
    /// CTRL_MODE of the emulated motor (a CTRL_MODE write it answers sets it).
    mode: i64,
    /// The feedback vector answering every command; `None`: by `reply_state` (enable →
    /// `fb_enabled`, disable → `fb_disabled`, others `fb_enabled`).
    feedback: Option<&'static str>,
    /// Frames sent before each reply (other motors' traffic on the same identifier).
    noise: Vec<CanFrame>,
}

impl Script {
    fn new(all: &Arc<BTreeMap<String, Vector>>) -> Self {
        Self {
            all: Arc::clone(all),
            mode: 1,
            feedback: None,
            noise: Vec::new(),
        }
    }

    /// The replies to `request` (and the new CTRL_MODE).
    fn answer(&mut self, request: &CanFrame) -> Vec<CanFrame> {
        let candidates = self
            .all
            .values()
            .filter(|v| text(v, "dir") == "h2m" && v.frame == *request);
        let mut chosen = None;
        for v in candidates {
            if !v.has("ctrl_mode") || int(v, "ctrl_mode") == self.mode {
                chosen = Some(v.clone());
            }
        }
        let Some(v) = chosen else {
            return Vec::new();
        };
        let mut out = self.noise.clone();
        match text(&v, "reply") {
            "register" => {
                let reply = &self.all[&format!("{}_reply", v.name)];
                if text(&v, "cmd") == "reg_write" && text(&v, "reg") == "CTRL_MODE" {
                    self.mode = int(reply, "value");
                }
                out.push(reply.frame);
            }
            "feedback" => {
                let name = self.feedback.unwrap_or(match v.fields.get("reply_state") {
                    Some(state) if state == "0x0" => "fb_disabled",
                    _ => "fb_enabled",
                });
                out.push(self.all[name].frame);
            }
            _ => return Vec::new(),
        }
        out
    }
}

/// Every frame the responder received.
type Log = Arc<Mutex<Vec<CanFrame>>>;

fn spawn_responder(node: VirtualNode, mut script: Script) -> Log {
    let log: Log = Arc::default();
    let seen = Arc::clone(&log);
    tokio::spawn(async move {
        while let Ok(received) = node.recv().await {
            seen.lock().unwrap().push(received.frame);
            for reply in script.answer(&received.frame) {
                if node.send(reply).await.is_err() {
                    return;
                }
            }
        }
    });
    log
}

struct Rig {
    all: Arc<BTreeMap<String, Vector>>,
    driver: DamiaoDriver,
    bus: VirtualBus,
}

impl Rig {
    fn new(config: DriverConfig) -> Self {
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let host: Arc<dyn CanBus> = Arc::new(bus.attach("host"));
        Self {
            all: Arc::new(vectors()),
            driver: DamiaoDriver::new(host, config),
            bus,
        }
    }

    fn responder(&self, edit: impl FnOnce(&mut Script)) -> Log {
        let mut script = Script::new(&self.all);
        edit(&mut script);
        spawn_responder(self.bus.attach("motor"), script)
    }

    fn dm4310(&self) -> DamiaoMotor {
        self.driver.motor(0x01, 0x11, Model::DM4310).unwrap()
    }

    fn frame(&self, name: &str) -> CanFrame {
        self.all[name].frame
    }
}

/// The decoded values of feedback vector `name`, within its tolerance.
fn assert_feedback(all: &BTreeMap<String, Vector>, name: &str, got: &driver::damiao::Feedback) {
    let v = &all[name];
    let tol = f(v, "tol");
    assert_eq!(i64::from(got.state.code()), int(v, "state"), "{name}");
    assert!(
        (f64::from(got.position_rad) - f(v, "pos_rad")).abs() <= tol,
        "{name}"
    );
    assert!(
        (f64::from(got.velocity_rad_s) - f(v, "vel_rad_s")).abs() <= tol,
        "{name}"
    );
    assert!(
        (f64::from(got.torque_nm) - f(v, "torque_nm")).abs() <= tol,
        "{name}"
    );
    assert_eq!(i64::from(got.mos_temp_c), int(v, "t_mos_c"), "{name}");
    assert_eq!(i64::from(got.rotor_temp_c), int(v, "t_rotor_c"), "{name}");
}

#[tokio::test(start_paused = true)]
async fn requests_are_the_fixture_bytes_and_replies_decode() {
    let rig = Rig::new(DriverConfig::default());
    let log = rig.responder(|_| {});
    let motor = rig.dm4310();

    motor.set_control_mode(ControlMode::Mit).await.unwrap();
    assert_eq!(motor.control_mode(), Some(ControlMode::Mit));
    let enabled = motor.enable().await.unwrap();
    assert_eq!(enabled.state, MotorState::Enabled);
    assert_feedback(&rig.all, "fb_enabled", &enabled);
    assert_eq!(motor.last_feedback(), Some(enabled));
    motor.mit(1.0, 2.2, 50.0, 1.2, 1.5).await.unwrap();
    motor.mit(0.0, 0.0, 0.0, 0.0, 0.0).await.unwrap();
    motor.mit(12.5, -30.0, 500.0, 5.0, -10.0).await.unwrap();

    for (register, name) in [
        (Register::CtrlMode, "reg_read_ctrl_mode"),
        (Register::Timeout, "reg_read_timeout"),
        (Register::MstId, "reg_read_mst_id"),
        (Register::Pmax, "reg_read_pmax"),
        (Register::Vmax, "reg_read_vmax"),
        (Register::KtValue, "reg_read_kt_value"),
    ] {
        let got = motor.read_register(register).await.unwrap();
        let reply = &rig.all[&format!("{name}_reply")];
        assert_eq!(got.as_f64() as f32, f(reply, "value") as f32, "{name}");
    }
    let stored = motor
        .write_register(Register::KtValue, RegisterValue::F32(0.945))
        .await
        .unwrap();
    assert_eq!(stored, RegisterValue::F32(0.945));
    motor
        .write_register(Register::MstId, RegisterValue::U32(0x11))
        .await
        .unwrap();
    motor
        .write_register(Register::Pmax, RegisterValue::F32(12.5))
        .await
        .unwrap();
    motor
        .write_register(Register::Vmax, RegisterValue::F32(30.0))
        .await
        .unwrap();
    let timeout = motor.set_can_timeout(Duration::from_secs(1)).await.unwrap();
    assert_eq!(timeout, Duration::from_secs(1));
    let ranges = motor.read_ranges().await;
    // TMAX has no vector: the responder stays silent and the read times out by name.
    let Err(DamiaoError::Timeout {
        motor: 0x01,
        bus,
        request: "register read",
        ..
    }) = ranges
    else {
        panic!("{ranges:?}");
    };
    assert_eq!(bus, "host");
    motor.refresh().await.unwrap();
    motor.save().await.unwrap();
    motor.set_zero().await.unwrap();
    motor.clear_error().await.unwrap();
    let disabled = motor.disable().await.unwrap();
    assert_feedback(&rig.all, "fb_disabled", &disabled);
    tokio::time::sleep(Duration::from_millis(5)).await;

    let f = |name: &str| rig.frame(name);
    let expected = vec![
        f("reg_write_ctrl_mode_mit"),
        f("reg_read_ctrl_mode"),
        f("enable"),
        f("mit_positive"),
        f("mit_zero"),
        f("mit_range_ends"),
        f("reg_read_ctrl_mode"),
        f("reg_read_timeout"),
        f("reg_read_mst_id"),
        f("reg_read_pmax"),
        f("reg_read_vmax"),
        f("reg_read_kt_value"),
        f("reg_write_kt_value"),
        f("reg_write_mst_id"),
        f("reg_write_pmax"),
        f("reg_write_vmax"),
        f("reg_write_timeout"),
        f("reg_read_pmax"),
        f("reg_read_vmax"),
        codec_read_tmax(),
        f("refresh"),
        f("reg_save"),
        f("set_zero"),
        f("clear_error"),
        f("disable"),
    ];
    assert_eq!(*log.lock().unwrap(), expected);
}

/// The TMAX read (RID 23), which has no vector.
fn codec_read_tmax() -> CanFrame {
    CanFrame::standard(0x7FF, &[0x01, 0x00, 0x33, 23, 0, 0, 0, 0]).unwrap()
}

#[tokio::test(start_paused = true)]
async fn mode_commands_match_their_vectors_in_their_mode() {
    for (mode, len) in [
        (2, VelocityLen::Eight),
        (3, VelocityLen::Eight),
        (3, VelocityLen::Four),
        (4, VelocityLen::Eight),
    ] {
        let rig = Rig::new(DriverConfig {
            velocity_len: len,
            ..DriverConfig::default()
        });
        let log = rig.responder(|s| s.mode = mode);
        // A fresh handle does not know the mode: every command is sent.
        let motor = rig.dm4310();
        let sent = match mode {
            2 => {
                motor.pos_vel(1.5, 2.0).await.unwrap();
                motor.pos_vel(-0.75, 10.0).await.unwrap();
                vec![rig.frame("pos_vel"), rig.frame("pos_vel_negative")]
            }
            3 => {
                motor.velocity(5.0).await.unwrap();
                let name = match len {
                    VelocityLen::Four => "velocity_dlc4",
                    VelocityLen::Eight => "velocity_dlc8",
                };
                vec![rig.frame(name)]
            }
            _ => {
                motor.force_position(1.0, 5.0, 0.5).await.unwrap();
                motor.force_position(-3.0, 0.25, 0.125).await.unwrap();
                vec![rig.frame("force_pos"), rig.frame("force_pos_small")]
            }
        };
        assert_eq!(*log.lock().unwrap(), sent, "mode {mode}");
    }
}

#[tokio::test(start_paused = true)]
async fn a_command_for_another_mode_times_out_then_is_refused() {
    let rig = Rig::new(DriverConfig::default());
    let log = rig.responder(|_| {});
    let motor = rig.dm4310();
    // The motor is in MIT mode: the velocity command is ignored, the wait names motor and bus.
    let error = motor.velocity(5.0).await.unwrap_err();
    let message = error.to_string();
    assert!(
        matches!(
            error,
            DamiaoError::Timeout {
                motor: 0x01,
                request: "velocity command",
                ..
            }
        ),
        "{error:?}"
    );
    assert!(
        message.contains("0x01") && message.contains("host"),
        "{message}"
    );
    // Once the mode is known, such commands are refused without sending.
    assert_eq!(
        motor.read_register(Register::CtrlMode).await.unwrap(),
        RegisterValue::U32(1)
    );
    let before = log.lock().unwrap().len();
    for result in [
        motor.velocity(5.0).await,
        motor.pos_vel(1.0, 1.0).await,
        motor.force_position(1.0, 1.0, 0.5).await,
    ] {
        assert!(
            matches!(
                result,
                Err(DamiaoError::WrongMode {
                    mode: ControlMode::Mit,
                    ..
                })
            ),
            "{result:?}"
        );
    }
    assert_eq!(log.lock().unwrap().len(), before);
    motor.mit(1.0, 2.2, 50.0, 1.2, 1.5).await.unwrap();
}

#[tokio::test(start_paused = true)]
async fn a_mode_the_motor_does_not_take_is_reported() {
    let rig = Rig::new(DriverConfig::default());
    // The responder echoes the write but its read reply says MIT (value 1).
    rig.responder(|_| {});
    let motor = rig.dm4310();
    let result = motor.set_control_mode(ControlMode::PosVel).await;
    assert!(
        matches!(
            result,
            Err(DamiaoError::ModeNotApplied {
                wanted: ControlMode::PosVel,
                actual: 1,
                ..
            })
        ),
        "{result:?}"
    );
    assert_eq!(motor.control_mode(), Some(ControlMode::Mit));
}

#[tokio::test(start_paused = true)]
async fn error_states_are_motor_errors_with_their_name() {
    let names = [
        "fb_over_voltage",
        "fb_under_voltage",
        "fb_over_current",
        "fb_mos_over_temperature",
        "fb_rotor_over_temperature",
        "fb_communication_lost",
        "fb_overload",
    ];
    for name in names {
        let rig = Rig::new(DriverConfig::default());
        rig.responder(|s| s.feedback = Some(name));
        let motor = rig.dm4310();
        let error = motor.refresh().await.unwrap_err();
        let message = error.to_string();
        let DamiaoError::Motor(e) = error else {
            panic!("{name}: {error:?}");
        };
        let v = &rig.all[name];
        assert_eq!(e.state.name(), text(v, "state_name"));
        assert_eq!(i64::from(e.state.code()), int(v, "state"));
        assert_eq!((e.motor, e.bus.as_str()), (0x01, "host"));
        assert_feedback(&rig.all, name, &e.feedback);
        assert!(
            message.contains(text(v, "state_name")) && message.contains("0x01"),
            "{message}"
        );
        assert_eq!(motor.last_feedback(), Some(e.feedback));
    }
}

#[tokio::test(start_paused = true)]
async fn an_enable_answered_disabled_is_refused() {
    let rig = Rig::new(DriverConfig::default());
    rig.responder(|s| s.feedback = Some("fb_disabled"));
    let motor = rig.dm4310();
    let result = motor.enable().await;
    assert!(
        matches!(
            result,
            Err(DamiaoError::EnableRefused {
                motor: 0x01,
                state: MotorState::Disabled,
                ..
            })
        ),
        "{result:?}"
    );
}

#[tokio::test(start_paused = true)]
async fn replies_of_other_motors_are_ignored() {
    let rig = Rig::new(DriverConfig::default());
    // On our MST_ID, first another motor's feedback (nibble 2) and another motor's register
    // reply, then ours.
    let mut foreign = rig.frame("fb_over_voltage").data().to_vec();
    foreign[0] = 0x82;
    let foreign = CanFrame::standard(0x11, &foreign).unwrap();
    let other_register = CanFrame::standard(0x11, &[0x02, 0x00, 0x33, 0x0A, 3, 0, 0, 0]).unwrap();
    rig.responder(|s| s.noise = vec![foreign, other_register]);
    let motor = rig.dm4310();
    let fb = motor.refresh().await.unwrap();
    assert_feedback(&rig.all, "fb_enabled", &fb);
    assert_eq!(
        motor.read_register(Register::CtrlMode).await.unwrap(),
        RegisterValue::U32(1)
    );

    // Only a foreign reply: the request times out.
    let rig = Rig::new(DriverConfig::default());
    let injector = rig.bus.attach("injector");
    let motor = rig.dm4310();
    let refresh = tokio::spawn(async move { motor.refresh().await });
    tokio::time::sleep(Duration::from_millis(1)).await;
    injector.send(foreign).await.unwrap();
    let result = refresh.await.unwrap();
    assert!(
        matches!(result, Err(DamiaoError::Timeout { motor: 0x01, .. })),
        "{result:?}"
    );
}

#[tokio::test(start_paused = true)]
async fn motors_on_one_bus_are_routed_by_mst_id() {
    let rig = Rig::new(DriverConfig::default());
    let a = rig.dm4310();
    let b = rig.driver.motor(0x03, 0x13, Model::DM4340).unwrap();
    // A responder per motor, answering a refresh with its model's feedback vector.
    for (esc, reply) in [(0x01u8, "fb_enabled"), (0x03, "fb_dm4340")] {
        let node = rig.bus.attach("motor");
        let frame = rig.frame(reply);
        tokio::spawn(async move {
            while let Ok(received) = node.recv().await {
                let d = received.frame.data();
                if received.frame.raw_id() == 0x7FF && d.len() == 8 && d[0] == esc && d[2] == 0xCC {
                    let _ = node.send(frame).await;
                }
            }
        });
    }
    let (fa, fb) = tokio::join!(a.refresh(), b.refresh());
    assert_feedback(&rig.all, "fb_enabled", &fa.unwrap());
    // DM4340 decoded with VMAX 10.
    assert_feedback(&rig.all, "fb_dm4340", &fb.unwrap());

    // One handle per ESC_ID and per MST_ID; identifiers and ranges are checked.
    let in_use = |r: Result<DamiaoMotor, DamiaoError>, id| {
        assert!(
            matches!(r, Err(DamiaoError::IdInUse { id: got }) if got == id),
            "{r:?}"
        );
    };
    in_use(rig.driver.motor(0x05, 0x11, Model::DM4310), 0x11);
    in_use(rig.driver.motor(0x01, 0x15, Model::DM4310), 0x01);
    assert!(matches!(
        rig.driver.motor(0x4FF, 0x15, Model::DM4310),
        Err(DamiaoError::InvalidId { esc_id: 0x4FF, .. })
    ));
    assert!(matches!(
        rig.driver.motor(0x05, 0x7FF, Model::DM4310),
        Err(DamiaoError::InvalidId { mst_id: 0x7FF, .. })
    ));
    let bad = driver::damiao::Ranges::new(12.5, f32::NAN, 10.0);
    assert!(matches!(
        rig.driver.motor_with_ranges(0x05, 0x15, Model::DM4310, bad),
        Err(DamiaoError::InvalidRanges { .. })
    ));
    // Dropping a handle frees its identifiers.
    drop(a);
    assert!(rig.driver.motor(0x01, 0x11, Model::DM4310).is_ok());
}

#[tokio::test(start_paused = true)]
async fn bad_values_are_refused_without_sending() {
    let rig = Rig::new(DriverConfig::default());
    let log = rig.responder(|_| {});
    let motor = rig.dm4310();
    let out_of_range = |r: Result<driver::damiao::Feedback, DamiaoError>, field: &str| {
        assert!(
            matches!(&r, Err(DamiaoError::OutOfRange { field: got, .. }) if *got == field),
            "{field}: {r:?}"
        );
    };
    out_of_range(motor.mit(12.6, 0.0, 0.0, 0.0, 0.0).await, "p_des_rad");
    out_of_range(motor.mit(0.0, -30.5, 0.0, 0.0, 0.0).await, "v_des_rad_s");
    out_of_range(motor.mit(0.0, 0.0, f32::NAN, 0.0, 0.0).await, "kp");
    out_of_range(motor.mit(0.0, 0.0, 0.0, 5.1, 0.0).await, "kd");
    out_of_range(
        motor.mit(0.0, 0.0, 0.0, 0.0, f32::INFINITY).await,
        "t_ff_nm",
    );
    out_of_range(motor.pos_vel(1.0, -1.0).await, "v_limit_rad_s");
    out_of_range(motor.velocity(f32::NAN).await, "v_des_rad_s");
    out_of_range(motor.force_position(1.0, 100.5, 0.5).await, "v_limit_rad_s");
    out_of_range(motor.force_position(1.0, 1.0, 1.01).await, "i_limit");
    let r = motor
        .write_register(Register::Gr, RegisterValue::F32(10.0))
        .await;
    assert!(
        matches!(
            r,
            Err(DamiaoError::ReadOnlyRegister {
                register: Register::Gr
            })
        ),
        "{r:?}"
    );
    let r = motor
        .write_register(Register::CtrlMode, RegisterValue::F32(1.0))
        .await;
    assert!(
        matches!(
            r,
            Err(DamiaoError::WrongValueType {
                register: Register::CtrlMode,
                ..
            })
        ),
        "{r:?}"
    );
    let r = motor
        .write_register(Register::Pmax, RegisterValue::F32(f32::NAN))
        .await;
    assert!(matches!(r, Err(DamiaoError::OutOfRange { .. })), "{r:?}");
    tokio::time::sleep(Duration::from_millis(5)).await;
    assert!(log.lock().unwrap().is_empty());
}
