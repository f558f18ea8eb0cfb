//! Damiao faults as front ends reach them ([`FaultTarget`] on [`DamiaoMonitor`]): the table of
//! [`crate::damiao::faults`] addressed by the motor's ESC_ID (`motor`), checked at the
//! addressed motor's power-on thresholds, then applied by the runner, which builds the fault
//! again against the thresholds the motor holds by then (a host may have written OV_Value).

use super::faults::{Fault, Thresholds};
use super::firmware::MAX_ID;
use super::model::Model;
use super::runner::DamiaoMonitor;
use crate::fault_args::{FaultArgError, FaultArgValue, FaultArgs};
use crate::fault_desk::{FaultInfo, FaultTarget, ParamInfo};
use crate::piper::faults::Shown;

/// The argument naming the motor a fault is on: its ESC_ID.
pub const MOTOR: &str = "motor";

/// A fault on one motor, as the desk builds it from a front end's arguments.
#[derive(Debug, Clone, PartialEq)]
pub struct MotorFault {
    /// The ESC_ID of the motor it is on.
    pub esc_id: u16,
    /// The fault.
    pub fault: Fault,
    /// Its values as given (`voltage_v`, `temperature_c`; empty: the defaults of the
    /// thresholds the motor holds when it is applied).
    pub values: FaultArgs,
}

impl DamiaoMonitor {
    /// The model of the motor that powered on with `esc_id` (the first motor's for an id none
    /// powered on with: a host moved it, and the runner finds it where it is now).
    fn model_at(&self, esc_id: u16) -> Model {
        self.power_on_ids()
            .iter()
            .position(|&id| id == esc_id)
            .or((!self.models().is_empty()).then_some(0))
            .map_or(Model::DM4310, |k| self.models()[k])
    }

    /// The fault `name` on the motor `args` name, its values checked (`clearing`: only that
    /// they are its own).
    fn read(
        &self,
        name: &str,
        args: &FaultArgs,
        clearing: bool,
    ) -> Result<MotorFault, FaultArgError> {
        let fault = Fault::named(name)?;
        // An argument the fault does not take is refused first, by name (its parameters'
        // names are every model's; only their ranges differ).
        let names = fault.info(&Thresholds::power_on(Model::DM4310));
        let known: Vec<&str> = std::iter::once(MOTOR)
            .chain(names.params.iter().map(|p| p.name))
            .collect();
        args.only(name, &known)?;
        let esc_id = read_motor(fault, args)?;
        let limits = Thresholds::power_on(self.model_at(esc_id));
        let mut values = FaultArgs::new();
        for (arg, value) in args.iter().filter(|(arg, _)| *arg != MOTOR) {
            values.push(arg, value.clone());
        }
        if clearing {
            fault.build_to_clear(&values, &limits)?;
        } else {
            fault.build(&values, &limits)?;
        }
        Ok(MotorFault {
            esc_id,
            fault,
            values,
        })
    }
}

/// `motor`: given, a whole number, an 11-bit identifier.
fn read_motor(fault: Fault, args: &FaultArgs) -> Result<u16, FaultArgError> {
    let value = match args.get(MOTOR) {
        None => return Err(FaultArgError::missing(fault.name(), MOTOR)),
        Some(FaultArgValue::Number(v)) if v.is_finite() && v.fract() == 0.0 => *v,
        Some(other) => {
            return Err(FaultArgError::at(
                MOTOR,
                format!("`{MOTOR}` must be a whole number (an ESC_ID), got {other}"),
            ))
        }
    };
    if (0.0..=f64::from(MAX_ID)).contains(&value) {
        // Whole and within 0..=0x7FF: the cast is exact.
        Ok(value as u16)
    } else {
        Err(FaultArgError::at(
            MOTOR,
            format!(
                "`{MOTOR}`: ESC_ID {} out of range, expected 0..={MAX_ID}",
                Shown(value)
            ),
        ))
    }
}

#[async_trait::async_trait]
impl FaultTarget for DamiaoMonitor {
    type Fault = MotorFault;

    /// The table at the first motor's power-on thresholds (another model's ranges are
    /// checked when its fault is built), each fault led by `motor`.
    fn fault_table(&self) -> Vec<FaultInfo> {
        let first = self.power_on_ids().first().copied();
        let limits = Thresholds::power_on(self.model_at(first.unwrap_or(0)));
        Fault::ALL
            .iter()
            .map(|fault| {
                let mut info = fault.info(&limits);
                let motor =
                    ParamInfo::required(MOTOR, "ESC_ID of the motor (its command identifier)")
                        .within(0.0, f64::from(MAX_ID))
                        .suggesting(first.map(|id| FaultArgValue::Number(f64::from(id))));
                info.params.insert(0, motor);
                info
            })
            .collect()
    }

    fn build(&self, name: &str, args: &FaultArgs) -> Result<MotorFault, FaultArgError> {
        self.read(name, args, false)
    }

    fn build_to_clear(&self, name: &str, args: &FaultArgs) -> Result<MotorFault, FaultArgError> {
        self.read(name, args, true)
    }

    fn label(&self, fault: &MotorFault) -> String {
        let mut shown = fault.fault.name().to_owned();
        for (arg, value) in fault.values.iter() {
            shown.push_str(&format!(" {arg}={value}"));
        }
        format!("{shown} on motor {}", fault.esc_id)
    }

    fn same_site(&self, a: &MotorFault, b: &MotorFault) -> bool {
        a.esc_id == b.esc_id && a.fault == b.fault
    }

    async fn inject(&self, fault: MotorFault) -> Result<(), String> {
        DamiaoMonitor::inject(self, fault.esc_id, fault.fault.name(), &fault.values)
            .await
            .map_err(|e| e.to_string())
    }

    async fn clear(&self, fault: MotorFault) -> Result<(), String> {
        DamiaoMonitor::clear(self, fault.esc_id, fault.fault.name(), &fault.values)
            .await
            .map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use bus::virtual_bus::{VirtualBus, VirtualBusConfig};

    use super::*;
    use crate::damiao::{DamiaoBus, DamiaoConfig, MotorConfig};
    use crate::fault_desk::{FaultAction, FaultCommandError, FaultDesk, Faults};

    fn number(name: &str, x: f64) -> FaultArgs {
        FaultArgs::new().with(name, FaultArgValue::Number(x))
    }

    #[tokio::test(start_paused = true)]
    async fn the_desk_reaches_a_motor_by_its_esc_id_with_the_fault_table_s_ranges() {
        let bus = VirtualBus::new(VirtualBusConfig::default());
        let config = DamiaoConfig::new(vec![
            MotorConfig::new(3, Model::DM4340),
            MotorConfig::new(4, Model::DM4310_48V),
        ]);
        let emulator = DamiaoBus::spawn(config, Arc::new(bus.attach("motors"))).unwrap();
        let desk = FaultDesk::new(emulator.monitor());

        // The table: every fault led by `motor`, suggesting the first motor.
        let table = desk.table();
        assert_eq!(table.len(), Fault::ALL.len());
        let motor = &table[0].params[0];
        assert_eq!(
            (motor.name, motor.default.clone(), motor.max),
            (MOTOR, Some(FaultArgValue::Number(3.0)), Some(2047.0))
        );
        assert_eq!(table[0].params[1].name, "voltage_v");

        let done = desk
            .apply(FaultAction::Inject, "over_voltage", &number("motor", 3.0))
            .await;
        assert_eq!(done, Ok("injected over_voltage on motor 3".into()));
        // The 48 V motor's threshold is its own: 40 V does not trip it.
        let hot = number("motor", 4.0).with("voltage_v", FaultArgValue::Number(40.0));
        let refused = desk.apply(FaultAction::Inject, "over_voltage", &hot).await;
        assert!(
            matches!(&refused, Err(FaultCommandError::Refused(e)) if e.message.contains("does not trip over_voltage")),
            "{refused:?}"
        );
        let heat = number("motor", 4.0).with("temperature_c", FaultArgValue::Number(150.0));
        desk.apply(FaultAction::Inject, "coil_over_temperature", &heat)
            .await
            .unwrap();
        assert_eq!(
            desk.active(),
            [
                "over_voltage on motor 3",
                "coil_over_temperature temperature_c=150 on motor 4"
            ]
        );
        let snapshot = desk.target().snapshot().await.unwrap();
        assert_eq!(snapshot[0].faults, ["over_voltage"]);
        assert_eq!(snapshot[1].faults, ["coil_over_temperature"]);

        // Refusals name the argument, with `motor` among those a fault takes.
        for (args, message) in [
            (FaultArgs::new(), "`over_voltage` needs `motor`"),
            (
                number("motor", 5000.0),
                "`motor`: ESC_ID 5000 out of range, expected 0..=2047",
            ),
            (
                number("motor", 3.0).with("joint", FaultArgValue::Number(1.0)),
                "fault `over_voltage` has no argument `joint`; it takes: motor, voltage_v",
            ),
            (
                FaultArgs::new().with("motor", FaultArgValue::Text("x".into())),
                "`motor` must be a whole number (an ESC_ID), got `x`",
            ),
        ] {
            let refused = desk.apply(FaultAction::Inject, "over_voltage", &args).await;
            assert_eq!(refused.map_err(|e| e.to_string()), Err(message.to_owned()));
        }
        // A motor no one answers as: the runner says so.
        let nobody = desk
            .apply(FaultAction::Inject, "overload", &number("motor", 9.0))
            .await;
        assert_eq!(
            nobody,
            Err(FaultCommandError::Emulator(
                "no motor with ESC_ID 0x009".into()
            ))
        );

        // Clearing needs the motor alone; the latch stays until the host's FB.
        let cleared = desk
            .apply(FaultAction::Clear, "over_voltage", &number("motor", 3.0))
            .await;
        assert_eq!(cleared, Ok("cleared over_voltage on motor 3".into()));
        assert_eq!(
            desk.active(),
            ["coil_over_temperature temperature_c=150 on motor 4"]
        );
        emulator.shutdown().await;
        let gone = desk
            .apply(FaultAction::Inject, "overload", &number("motor", 3.0))
            .await;
        assert!(
            matches!(gone, Err(FaultCommandError::Emulator(_))),
            "{gone:?}"
        );
    }
}
