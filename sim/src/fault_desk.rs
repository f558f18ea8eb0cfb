//! How a front end reaches a running emulator's faults: one contract every emulator kind
//! implements ([`FaultTarget`]), and one desk ([`FaultDesk`]) that builds a named fault from a
//! front end's arguments, applies it and remembers what is active.
//!
//! The web view's fault panel (`armhil sim <kind> --ui`) and the Python emulators'
//! `inject`/`clear`/`faults` reach every kind through this module and nothing else, so a new
//! kind gets both by implementing [`FaultTarget`] on its monitor (beside its fault table, in
//! `sim::<kind>::faults`). Scenario files use the same builders with spans of their own.

use std::fmt;
use std::sync::{Mutex, PoisonError};

use serde::Serialize;

use crate::fault_args::{FaultArgError, FaultArgValue, FaultArgs};

/// One parameter of a fault as a front end offers it (a form field, a keyword argument).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamInfo {
    /// Its name (units in the name).
    pub name: &'static str,
    /// What it sets, for a tooltip or a docstring.
    pub description: String,
    /// Whether the fault is refused without it.
    pub required: bool,
    /// The value a form starts with (for a required parameter), or the one taken when it is
    /// omitted (for an optional one).
    pub default: Option<FaultArgValue>,
    /// Smallest number accepted (`None`: not a number, or unbounded).
    pub min: Option<f64>,
    /// Largest number accepted.
    pub max: Option<f64>,
    /// The words a word parameter accepts (empty for numbers and free words).
    pub words: Vec<&'static str>,
}

impl ParamInfo {
    /// A required parameter with no suggested value, range or words.
    pub fn required(name: &'static str, description: impl Into<String>) -> Self {
        Self {
            name,
            description: description.into(),
            required: true,
            default: None,
            min: None,
            max: None,
            words: Vec::new(),
        }
    }

    /// The same, accepting numbers from `min` to `max` inclusive.
    pub fn within(mut self, min: f64, max: f64) -> Self {
        self.min = Some(min);
        self.max = Some(max);
        self
    }

    /// The same, with `value` suggested (or taken when omitted, if not required).
    pub fn suggesting(mut self, value: Option<FaultArgValue>) -> Self {
        self.default = value;
        self
    }
}

/// One fault of an emulator's table as a front end lists it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FaultInfo {
    /// Its name (as in scenario files).
    pub name: &'static str,
    /// What it does to the device, in one line.
    pub description: String,
    /// Its parameters, in the table's order.
    pub params: Vec<ParamInfo>,
}

/// A running emulator whose faults front ends can set: implemented by each kind's monitor
/// (the cloneable view of a running emulator) beside its fault table.
#[async_trait::async_trait]
pub trait FaultTarget: Send + Sync + 'static {
    /// A fault ready to apply, with its site (joint, motor, bus) and values.
    type Fault: Clone + Send + Sync + 'static;

    /// Every fault this emulator takes, for a menu (the web view) or a listing (Python).
    fn fault_table(&self) -> Vec<FaultInfo>;

    /// The fault `name` with `args`, by the kind's one fault builder (its ranges, defaults
    /// and messages).
    fn build(&self, name: &str, args: &FaultArgs) -> Result<Self::Fault, FaultArgError>;

    /// The fault `name` to clear: its site must be given, its values may be left out.
    fn build_to_clear(&self, name: &str, args: &FaultArgs) -> Result<Self::Fault, FaultArgError> {
        self.build(name, args)
    }

    /// The fault in words, as a front end shows it applied and active (`stall joint 2`,
    /// `over_temperature on motor 5`).
    fn label(&self, fault: &Self::Fault) -> String;

    /// Whether `a` and `b` sit at the same place: injecting one replaces the other, clearing
    /// one clears the other.
    fn same_site(&self, a: &Self::Fault, b: &Self::Fault) -> bool;

    /// Whether the fault lasts until cleared (`false`: an event, such as a dropped
    /// connection, that leaves nothing to clear).
    fn lasts(&self, _fault: &Self::Fault) -> bool {
        true
    }

    /// Apply `fault`; `Err` says why the emulator refused it (it has stopped, say).
    async fn inject(&self, fault: Self::Fault) -> Result<(), String>;

    /// Remove `fault`'s cause (what the device latched stays latched, as on the hardware).
    async fn clear(&self, fault: Self::Fault) -> Result<(), String>;
}

/// Inject or clear.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultAction {
    /// Apply the fault.
    Inject,
    /// Remove its cause.
    Clear,
}

/// Why a front end's fault command did nothing.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FaultCommandError {
    /// The fault could not be built from the arguments (a scenario's, a page's or Python's
    /// mistake; Python raises `ValueError`).
    #[error("{0}")]
    Refused(FaultArgError),
    /// The emulator did not take it (it has stopped, say).
    #[error("{0}")]
    Emulator(String),
}

/// A front end's fault desk for one emulator: builds, applies and remembers the faults it
/// applied and has not cleared, with their labels.
pub struct FaultDesk<T: FaultTarget> {
    target: T,
    active: Mutex<Vec<(String, T::Fault)>>,
}

impl<T: FaultTarget> fmt::Debug for FaultDesk<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FaultDesk")
            .field("active", &self.active())
            .finish_non_exhaustive()
    }
}

impl<T: FaultTarget> FaultDesk<T> {
    /// A desk for `target`, nothing active.
    pub fn new(target: T) -> Self {
        Self {
            target,
            active: Mutex::new(Vec::new()),
        }
    }

    /// The emulator it reaches.
    pub fn target(&self) -> &T {
        &self.target
    }
}

/// A fault desk with its emulator's kind out of sight: what the web view and the Python
/// emulators hold.
#[async_trait::async_trait]
pub trait Faults: Send + Sync + fmt::Debug {
    /// Every fault the emulator takes.
    fn table(&self) -> Vec<FaultInfo>;

    /// Build the fault `name` from `args` and apply it (`Inject`) or remove it (`Clear`);
    /// `Ok` says what was done (`injected stall on joint 2`).
    async fn apply(
        &self,
        action: FaultAction,
        name: &str,
        args: &FaultArgs,
    ) -> Result<String, FaultCommandError>;

    /// The faults applied here and not cleared, by label, oldest first.
    fn active(&self) -> Vec<String>;
}

#[async_trait::async_trait]
impl<T: FaultTarget> Faults for FaultDesk<T> {
    fn table(&self) -> Vec<FaultInfo> {
        self.target.fault_table()
    }

    async fn apply(
        &self,
        action: FaultAction,
        name: &str,
        args: &FaultArgs,
    ) -> Result<String, FaultCommandError> {
        let target = &self.target;
        let fault = match action {
            FaultAction::Inject => target.build(name, args),
            FaultAction::Clear => target.build_to_clear(name, args),
        }
        .map_err(FaultCommandError::Refused)?;
        let label = target.label(&fault);
        let lasts = target.lasts(&fault);
        match action {
            FaultAction::Inject => target.inject(fault.clone()).await,
            FaultAction::Clear => target.clear(fault.clone()).await,
        }
        .map_err(FaultCommandError::Emulator)?;
        let mut active = self.active.lock().unwrap_or_else(PoisonError::into_inner);
        active.retain(|(_, f)| !target.same_site(f, &fault));
        Ok(match action {
            FaultAction::Inject => {
                if lasts {
                    active.push((label.clone(), fault));
                }
                format!("injected {label}")
            }
            FaultAction::Clear => format!("cleared {label}"),
        })
    }

    fn active(&self) -> Vec<String> {
        self.active
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .iter()
            .map(|(label, _)| label.clone())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicBool, Ordering};

    use super::*;

    /// A lamp on numbered sockets: `on` (socket, brightness 0..=1) lasts, `blink` is an event.
    #[derive(Default)]
    struct Lamps {
        stopped: AtomicBool,
    }

    #[derive(Debug, Clone, PartialEq)]
    enum Lamp {
        On { socket: u8, brightness: f64 },
        Blink,
    }

    #[async_trait::async_trait]
    impl FaultTarget for Lamps {
        type Fault = Lamp;

        fn fault_table(&self) -> Vec<FaultInfo> {
            vec![FaultInfo {
                name: "on",
                description: "a lamp lit".into(),
                params: vec![ParamInfo::required("socket", "which")],
            }]
        }

        fn build(&self, name: &str, args: &FaultArgs) -> Result<Lamp, FaultArgError> {
            let number = |arg: &str| match args.get(arg) {
                Some(FaultArgValue::Number(x)) => Ok(*x),
                _ => Err(FaultArgError::at(arg, format!("`{arg}` must be a number"))),
            };
            match name {
                "on" => Ok(Lamp::On {
                    socket: number("socket")? as u8,
                    brightness: number("brightness")?,
                }),
                "blink" => Ok(Lamp::Blink),
                _ => Err(FaultArgError::whole(format!("no fault `{name}`"))),
            }
        }

        fn build_to_clear(&self, name: &str, args: &FaultArgs) -> Result<Lamp, FaultArgError> {
            let with_value = args.clone().with("brightness", FaultArgValue::Number(0.0));
            self.build(name, &with_value)
        }

        fn label(&self, fault: &Lamp) -> String {
            match fault {
                Lamp::On { socket, .. } => format!("on at {socket}"),
                Lamp::Blink => "blink".into(),
            }
        }

        fn same_site(&self, a: &Lamp, b: &Lamp) -> bool {
            match (a, b) {
                (Lamp::On { socket: x, .. }, Lamp::On { socket: y, .. }) => x == y,
                _ => false,
            }
        }

        fn lasts(&self, fault: &Lamp) -> bool {
            *fault != Lamp::Blink
        }

        async fn inject(&self, _fault: Lamp) -> Result<(), String> {
            if self.stopped.load(Ordering::Relaxed) {
                Err("stopped".into())
            } else {
                Ok(())
            }
        }

        async fn clear(&self, fault: Lamp) -> Result<(), String> {
            self.inject(fault).await
        }
    }

    fn number(name: &str, x: f64) -> FaultArgs {
        FaultArgs::new().with(name, FaultArgValue::Number(x))
    }

    #[tokio::test]
    async fn the_desk_keeps_one_active_fault_per_site_and_forgets_events() {
        let desk = FaultDesk::new(Lamps::default());
        let on = |socket: f64, brightness: f64| {
            number("socket", socket).with("brightness", FaultArgValue::Number(brightness))
        };
        let done = desk.apply(FaultAction::Inject, "on", &on(1.0, 0.5)).await;
        assert_eq!(done, Ok("injected on at 1".into()));
        desk.apply(FaultAction::Inject, "on", &on(2.0, 0.5))
            .await
            .unwrap();
        // The same socket again replaces, it does not add.
        desk.apply(FaultAction::Inject, "on", &on(1.0, 0.9))
            .await
            .unwrap();
        desk.apply(FaultAction::Inject, "blink", &FaultArgs::new())
            .await
            .unwrap();
        assert_eq!(desk.active(), ["on at 2", "on at 1"]);
        // Clearing needs the site only.
        let cleared = desk
            .apply(FaultAction::Clear, "on", &number("socket", 2.0))
            .await;
        assert_eq!(cleared, Ok("cleared on at 2".into()));
        assert_eq!(desk.active(), ["on at 1"]);
    }

    #[tokio::test]
    async fn a_refused_fault_or_a_stopped_emulator_changes_nothing() {
        let desk = FaultDesk::new(Lamps::default());
        let refused = desk
            .apply(FaultAction::Inject, "on", &number("socket", 1.0))
            .await;
        assert_eq!(
            refused,
            Err(FaultCommandError::Refused(FaultArgError::at(
                "brightness",
                "`brightness` must be a number"
            )))
        );
        desk.target().stopped.store(true, Ordering::Relaxed);
        let args = number("socket", 1.0).with("brightness", FaultArgValue::Number(1.0));
        let gone = desk.apply(FaultAction::Inject, "on", &args).await;
        assert_eq!(gone, Err(FaultCommandError::Emulator("stopped".into())));
        assert!(desk.active().is_empty());
        assert_eq!(desk.table()[0].params[0].name, "socket");
    }
}
