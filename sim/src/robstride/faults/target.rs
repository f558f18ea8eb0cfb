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
                params: vec![ParamInfo::required(MOTOR.name, "CAN ID of the motor")
                    .within(f64::from(MOTOR.min), f64::from(MOTOR.max))
                    .suggesting(first.map(|id| FaultArgValue::Number(f64::from(id))))],
            })
            .collect()
    }

    fn build(&self, name: &str, args: &FaultArgs) -> Result<MotorFault, FaultArgError> {
        Fault::named(name)?.build(args)
    }

    fn label(&self, fault: &MotorFault) -> String {
        format!("{} on motor {}", fault.fault.name(), fault.motor)
    }

    fn same_site(&self, a: &MotorFault, b: &MotorFault) -> bool {
        a == b
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
