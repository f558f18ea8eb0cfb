//! RobStride faults as front ends reach them ([`FaultTarget`] on [`RobstrideMonitor`]): the
//! table above addressed by CAN ID, the one builder, and the runner's inject and clear.

use super::{Fault, MotorFault, MOTOR};
use crate::fault_args::{FaultArgError, FaultArgValue, FaultArgs};
use crate::fault_desk::{FaultInfo, FaultTarget, ParamInfo};
use crate::robstride::RobstrideMonitor;

#[async_trait::async_trait]
impl FaultTarget for RobstrideMonitor {
    type Fault = MotorFault;

    fn fault_table(&self) -> Vec<FaultInfo> {
        let first = self.configured_ids().first().copied();
        Fault::ALL
            .iter()
            .map(|&fault| FaultInfo {
                name: fault.name(),
                description: fault.description(),
                params: std::iter::once(
                    ParamInfo::required(MOTOR.name, MOTOR.description)
                        .within(MOTOR.min as f64, MOTOR.max as f64)
                        .suggesting(first.map(|id| FaultArgValue::Number(f64::from(id)))),
                )
                .chain(fault.value_infos())
                .collect(),
            })
            .collect()
    }

    fn build(&self, name: &str, args: &FaultArgs) -> Result<MotorFault, FaultArgError> {
        Fault::named(name)?.build(args)
    }

    fn build_to_clear(&self, name: &str, args: &FaultArgs) -> Result<MotorFault, FaultArgError> {
        Fault::named(name)?.build_to_clear(args)
    }

    fn label(&self, fault: &MotorFault) -> String {
        format!("{} on motor {}", fault.fault.label(), fault.motor)
    }

    fn same_site(&self, a: &MotorFault, b: &MotorFault) -> bool {
        a.motor == b.motor && a.fault.same_kind(b.fault)
    }

    async fn inject(&self, fault: MotorFault) -> Result<(), String> {
        RobstrideMonitor::inject(self, fault.motor, fault.fault)
            .await
            .map_err(|e| e.to_string())
    }

    async fn clear(&self, fault: MotorFault) -> Result<(), String> {
        RobstrideMonitor::clear(self, fault.motor, fault.fault)
            .await
            .map_err(|e| e.to_string())
    }
}
