//! Realman faults as front ends reach them ([`FaultTarget`] on [`RealmanMonitor`]): the table
//! above, the one builder, and the controller's inject and clear. The controller clears a
//! fault by kind, so clearing needs only the name.

use super::{build_fault, RealmanFault, RealmanFaultKind, PEER_IP};
use crate::fault_args::{FaultArgError, FaultArgs};
use crate::fault_desk::{FaultInfo, FaultTarget, ParamInfo};
use crate::realman::RealmanMonitor;

/// A built fault to inject, or the kind to clear.
#[derive(Debug, Clone, PartialEq)]
pub enum RealmanFaultCommand {
    /// Inject this fault.
    Inject(RealmanFault),
    /// Clear whatever fault of this kind is set.
    Clear(RealmanFaultKind),
}

impl RealmanFaultCommand {
    fn kind(&self) -> RealmanFaultKind {
        match self {
            Self::Inject(fault) => fault.kind(),
            Self::Clear(kind) => *kind,
        }
    }
}

/// The table as a front end lists it: every parameter required and whole, with its range;
/// `connection_drop`'s optional `peer_ip` (one client's address) last.
pub fn fault_table() -> Vec<FaultInfo> {
    RealmanFaultKind::ALL
        .iter()
        .map(|&kind| {
            let mut params: Vec<ParamInfo> = kind
                .params()
                .iter()
                // Every range is at most 16 bits wide, exact in f64.
                .map(|p| {
                    ParamInfo::required(p.name, p.description).within(p.min as f64, p.max as f64)
                })
                .collect();
            if kind == RealmanFaultKind::ConnectionDrop {
                params.push(ParamInfo {
                    required: false,
                    ..ParamInfo::required(
                        PEER_IP,
                        "drop only this client's connections (IP address)",
                    )
                });
            }
            FaultInfo {
                name: kind.name(),
                description: kind.description().to_owned(),
                params,
            }
        })
        .collect()
}

/// The clear of fault `name`: the controller clears by kind, so a clear with the inject's
/// arguments works and needs none of them; one with an argument the fault does not take is
/// refused by name, as the inject is.
fn clear_command(name: &str, args: &FaultArgs) -> Result<RealmanFaultCommand, FaultArgError> {
    let kind = RealmanFaultKind::named(name)?;
    args.only(name, &kind.arg_names())?;
    Ok(RealmanFaultCommand::Clear(kind))
}

#[async_trait::async_trait]
impl FaultTarget for RealmanMonitor {
    type Fault = RealmanFaultCommand;

    fn fault_table(&self) -> Vec<FaultInfo> {
        fault_table()
    }

    fn build(&self, name: &str, args: &FaultArgs) -> Result<RealmanFaultCommand, FaultArgError> {
        build_fault(name, args).map(RealmanFaultCommand::Inject)
    }

    fn build_to_clear(
        &self,
        name: &str,
        args: &FaultArgs,
    ) -> Result<RealmanFaultCommand, FaultArgError> {
        clear_command(name, args)
    }

    fn label(&self, fault: &RealmanFaultCommand) -> String {
        fault.kind().name().to_owned()
    }

    fn same_site(&self, a: &RealmanFaultCommand, b: &RealmanFaultCommand) -> bool {
        a.kind() == b.kind()
    }

    fn lasts(&self, fault: &RealmanFaultCommand) -> bool {
        // A dropped connection is an event, not a state: nothing to clear.
        fault.kind() != RealmanFaultKind::ConnectionDrop
    }

    async fn inject(&self, fault: RealmanFaultCommand) -> Result<(), String> {
        match fault {
            RealmanFaultCommand::Inject(fault) => {
                RealmanMonitor::inject(self, fault).map_err(|e| e.to_string())
            }
            RealmanFaultCommand::Clear(kind) => {
                Err(format!("`{}` needs its values to be injected", kind.name()))
            }
        }
    }

    async fn clear(&self, fault: RealmanFaultCommand) -> Result<(), String> {
        RealmanMonitor::clear(self, fault.kind());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fault_args::FaultArgValue;

    /// Clearing takes the fault's name and, optionally, the inject's own arguments; any other
    /// argument is refused by name, as injecting it would be.
    #[test]
    fn a_clear_refuses_an_argument_the_fault_does_not_take() {
        let clear = |args: FaultArgs| clear_command("reply_delay", &args);
        let kind = RealmanFaultKind::named("reply_delay").expect("a fault");
        assert_eq!(
            clear(FaultArgs::new()),
            Ok(RealmanFaultCommand::Clear(kind))
        );
        assert!(clear(FaultArgs::new().with("delay_ms", FaultArgValue::Number(600.0))).is_ok());
        let bogus = clear(FaultArgs::new().with("bogus", FaultArgValue::Number(1.0)));
        assert_eq!(bogus.unwrap_err().arg.as_deref(), Some("bogus"));
    }
}
