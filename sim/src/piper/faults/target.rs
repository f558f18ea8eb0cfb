//! The Piper's faults as front ends reach them ([`FaultTarget`] on [`PiperMonitor`]): the
//! table above, the one builder, and the firmware's own inject and clear.

use super::{FaultKind, PiperFault};
use crate::fault_args::{FaultArgError, FaultArgValue, FaultArgs};
use crate::fault_desk::{FaultInfo, FaultTarget, ParamInfo};
use crate::piper::PiperMonitor;

/// The table as a front end lists it: each kind with its parameters, defaults and ranges.
pub fn fault_table() -> Vec<FaultInfo> {
    FaultKind::ALL
        .iter()
        .map(|kind| FaultInfo {
            name: kind.name(),
            description: kind.description().to_owned(),
            params: kind
                .params()
                .iter()
                .map(|p| ParamInfo {
                    name: p.name,
                    description: p.description.to_owned(),
                    required: p.required,
                    default: p.default.map(FaultArgValue::Number),
                    min: p.range.map(|r| r.0),
                    max: p.range.map(|r| r.1),
                    words: p.words.to_vec(),
                })
                .collect(),
        })
        .collect()
}

#[async_trait::async_trait]
impl FaultTarget for PiperMonitor {
    type Fault = PiperFault;

    fn fault_table(&self) -> Vec<FaultInfo> {
        fault_table()
    }

    fn build(&self, name: &str, args: &FaultArgs) -> Result<PiperFault, FaultArgError> {
        FaultKind::named(name)?.build(args)
    }

    fn build_to_clear(&self, name: &str, args: &FaultArgs) -> Result<PiperFault, FaultArgError> {
        FaultKind::named(name)?.build_to_clear(args)
    }

    fn label(&self, fault: &PiperFault) -> String {
        fault.to_string()
    }

    fn same_site(&self, a: &PiperFault, b: &PiperFault) -> bool {
        a.same_site(b)
    }

    async fn inject(&self, fault: PiperFault) -> Result<(), String> {
        PiperMonitor::inject(self, fault).map_err(|e| e.to_string())
    }

    async fn clear(&self, fault: PiperFault) -> Result<(), String> {
        PiperMonitor::clear(self, fault).map_err(|e| e.to_string())
    }
}
