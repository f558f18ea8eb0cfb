//! A fault's arguments as a scenario writes them, read one way for every device kind: any
//! keys, each a number or a word with its place in the file. Which arguments a fault takes,
//! their ranges and their messages are its emulator's one fault builder's (the same the web
//! view and Python call with the same arguments); a refusal is shown at the argument it is
//! about. So a fault that takes a new value needs nothing here: its kind's fault table says.

use std::collections::BTreeMap;

use serde::Deserialize;
use sim::fault_args::{FaultArgError, FaultArgValue, FaultArgs};

use super::{pos, Ctx, Pos, Res, S};

/// One argument's value as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub(crate) enum RawArgValue {
    /// A number (YAML integers and floats alike).
    Number(f64),
    /// `true` or `false`: no fault takes one, but the builder says so by the argument's name.
    Switch(bool),
    /// A word (a joint or bus name, a phase).
    Word(String),
}

/// A fault's arguments as written, by name.
#[derive(Debug, Default, Deserialize)]
#[serde(transparent)]
pub(crate) struct RawFaultArgs(BTreeMap<String, S<RawArgValue>>);

impl RawFaultArgs {
    /// Every argument, as the builders read them.
    pub(crate) fn args(&self) -> FaultArgs {
        self.args_except(&[])
    }

    /// Every argument but those named in `left_out` (read otherwise by the caller).
    pub(crate) fn args_except(&self, left_out: &[&str]) -> FaultArgs {
        let mut args = FaultArgs::new();
        for (name, value) in &self.0 {
            if left_out.contains(&name.as_str()) {
                continue;
            }
            args.push(
                name.clone(),
                match &value.value {
                    RawArgValue::Number(x) => FaultArgValue::Number(*x),
                    RawArgValue::Switch(on) => FaultArgValue::Text(on.to_string()),
                    RawArgValue::Word(w) => FaultArgValue::Text(w.clone()),
                },
            );
        }
        args
    }

    /// Where argument `name` is written, if it is.
    pub(crate) fn place(&self, name: &str) -> Option<Pos> {
        self.0.get(name).map(pos)
    }

    /// Argument `name` as a word with its place (a number written where a name was meant
    /// reads as its digits), or `None` when it is not written.
    pub(crate) fn word(&self, name: &str) -> Option<S<String>> {
        let value = self.0.get(name)?;
        let text = match &value.value {
            RawArgValue::Word(w) => w.clone(),
            // As Rust prints it: a whole number as its digits (`joint: 2` reads `2`).
            RawArgValue::Number(x) => x.to_string(),
            RawArgValue::Switch(on) => on.to_string(),
        };
        Some(S::new(text, value.referenced, value.defined))
    }

    /// The builder's error as a scenario error: at the argument it is about, else at `at`
    /// (the fault as a whole: its name, a missing argument).
    pub(crate) fn refusal(
        &self,
        ctx: &Ctx<'_>,
        at: Pos,
        error: FaultArgError,
    ) -> Box<super::ScenarioError> {
        let place = error.arg.as_deref().and_then(|arg| self.place(arg));
        ctx.err(place.unwrap_or(at), error.message)
    }

    /// The fault `build` makes of these arguments, or its refusal at the argument it is about.
    pub(crate) fn build<T>(
        &self,
        ctx: &Ctx<'_>,
        at: Pos,
        build: impl FnOnce(&FaultArgs) -> Result<T, FaultArgError>,
    ) -> Res<T> {
        build(&self.args()).map_err(|e| self.refusal(ctx, at, e))
    }
}
