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
        _args: &FaultArgs,
    ) -> Result<RealmanFaultCommand, FaultArgError> {
        // The controller clears by kind: a clear with the inject's arguments still works.
        RealmanFaultKind::named(name).map(RealmanFaultCommand::Clear)
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
