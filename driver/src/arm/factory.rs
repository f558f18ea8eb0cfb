//! The factory: parameters (typed, string pairs or a JSON file) to an arm of the right vendor.
//! Creating an arm opens nothing; [`super::ArmInterface::connect`] does.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use super::config::load_config;
use super::error::ArmResult;
use super::interface::ArmInterface;
use super::params::{ArmFactoryParam, Vendor};
use super::piper::PiperArm;
use super::realman::RealmanArm;

/// Creates an (unconnected) arm from validated parameters.
pub fn create_arm(param: ArmFactoryParam) -> Arc<dyn ArmInterface> {
    match param.arm_type {
        Vendor::Realman => Arc::new(RealmanArm::new(param)),
        Vendor::Piper => Arc::new(PiperArm::new(param)),
    }
}

/// Creates an arm from `vendor_type`, `name` and string parameters (the API's
/// `create_arm(vendor_type, name, params)`). An unknown vendor is `INVALID_ARGUMENT`; a
/// missing or malformed parameter is `PARAM_ERROR` naming the key.
pub fn create_arm_from_map(
    vendor_type: &str,
    name: &str,
    params: &BTreeMap<String, String>,
) -> ArmResult<Arc<dyn ArmInterface>> {
    let mut map = params.clone();
    map.insert("arm_type".into(), vendor_type.into());
    map.insert("arm_name".into(), name.into());
    Ok(create_arm(ArmFactoryParam::from_map(&map)?))
}

/// Creates an arm from a JSON configuration file; errors name the file, and the key (and
/// value) at fault.
pub fn create_arm_from_config(config_path: impl AsRef<Path>) -> ArmResult<Arc<dyn ArmInterface>> {
    Ok(create_arm(load_config(config_path)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::{AbcErrorCode, Method};

    fn map(pairs: &[(&str, &str)]) -> BTreeMap<String, String> {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    #[test]
    fn the_factory_picks_the_backend_by_vendor() {
        let realman = create_arm_from_map(
            "realman",
            "left_arm",
            &map(&[
                ("ip", "127.0.0.1"),
                ("port", "8080"),
                ("udp_ip", "127.0.0.1"),
                ("udp_port", "8089"),
                ("udp_cycle", "2"),
            ]),
        )
        .unwrap();
        assert_eq!(
            (realman.vendor(), realman.name()),
            (Vendor::Realman, "left_arm")
        );
        assert!(realman.supports(Method::SetArmPause));
        let piper = create_arm_from_map("piper", "right_arm", &map(&[])).unwrap();
        assert_eq!(piper.vendor(), Vendor::Piper);
        assert!(!piper.supports(Method::SetArmPause));
    }

    #[test]
    fn unknown_vendors_and_missing_keys_are_refused() {
        let e = create_arm_from_map("kuka", "a", &map(&[])).err().unwrap();
        assert_eq!(e.code, AbcErrorCode::InvalidArgument);
        let e = create_arm_from_map("realman", "a", &map(&[("ip", "127.0.0.1")]))
            .err()
            .unwrap();
        assert_eq!(e.code, AbcErrorCode::ParamError);
        assert!(e.message.contains("\"port\""), "{e}");
    }

    #[cfg(target_os = "linux")]
    #[tokio::test]
    async fn a_missing_can_interface_is_a_send_failure_naming_it() {
        let arm = create_arm(ArmFactoryParam::piper("p", "armhilnocan7"));
        let e = arm.connect().await.unwrap_err();
        assert_eq!(e.code, AbcErrorCode::ArmDataSendFailed, "{e}");
        assert!(e.message.contains("\"armhilnocan7\""), "{e}");
        assert_eq!(
            arm.get_joint_degree().await.unwrap_err().code,
            AbcErrorCode::NotInitialized
        );
    }

    #[tokio::test]
    async fn calls_before_connect_are_not_initialized() {
        let arm = create_arm_from_map("piper", "p", &map(&[])).unwrap();
        let e = arm.get_joint_degree().await.unwrap_err();
        assert_eq!(e.code, AbcErrorCode::NotInitialized);
        let e = arm.set_arm_pause().await.unwrap_err();
        assert_eq!(e.code, AbcErrorCode::NotImplemented);
    }
}
