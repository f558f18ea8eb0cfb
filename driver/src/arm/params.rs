//! `ArmFactoryParam`: the parameters that create an arm, validated from string key/value pairs.

use std::collections::BTreeMap;
use std::fmt;
use std::net::{IpAddr, Ipv4Addr};
use std::str::FromStr;

use super::error::{AbcErrorCode, ArmError};

/// The arm vendors the factory knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Vendor {
    /// Realman arm controllers (JSON over TCP, state over UDP).
    Realman,
    /// AgileX Piper (CAN).
    Piper,
}

impl Vendor {
    /// Every vendor.
    pub const ALL: [Self; 2] = [Self::Realman, Self::Piper];

    /// The name used in `arm_type`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Realman => "realman",
            Self::Piper => "piper",
        }
    }
}

impl fmt::Display for Vendor {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Vendor {
    type Err = ParamError;

    fn from_str(s: &str) -> Result<Self, ParamError> {
        Self::ALL
            .into_iter()
            .find(|v| v.name() == s)
            .ok_or_else(|| ParamError::UnknownVendor {
                value: s.to_string(),
            })
    }
}

/// Why a parameter set is not valid.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ParamError {
    /// A required key is absent.
    #[error("missing key {key:?}")]
    MissingKey {
        /// The key.
        key: &'static str,
    },
    /// A value does not parse as what the key needs.
    #[error("key {key:?}: {value:?} is not {expected}")]
    BadValue {
        /// The key.
        key: &'static str,
        /// The value given.
        value: String,
        /// What was expected.
        expected: &'static str,
    },
    /// A value parses but is outside its range.
    #[error("key {key:?}: {value} is outside {range}")]
    OutOfRange {
        /// The key.
        key: &'static str,
        /// The value given.
        value: String,
        /// The valid range.
        range: &'static str,
    },
    /// `arm_type` names no known vendor.
    #[error("unknown arm_type {value:?} (known: realman, piper)")]
    UnknownVendor {
        /// The value given.
        value: String,
    },
}

impl ParamError {
    /// The API code for this error.
    pub fn code(&self) -> AbcErrorCode {
        match self {
            Self::MissingKey { .. } | Self::BadValue { .. } => AbcErrorCode::ParamError,
            Self::OutOfRange { .. } => AbcErrorCode::ParamOutOfRange,
            Self::UnknownVendor { .. } => AbcErrorCode::InvalidArgument,
        }
    }
}

impl From<ParamError> for ArmError {
    fn from(e: ParamError) -> Self {
        ArmError::caused_by(e.code(), e)
    }
}

/// The CAN interface a Piper uses when the parameters name none.
pub const DEFAULT_CAN_INTERFACE: &str = "can0";

/// Everything needed to create an arm. Realman arms use the network fields, Piper arms the CAN
/// interface; fields a vendor does not use keep their defaults.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ArmFactoryParam {
    /// Vendor (`arm_type`).
    pub arm_type: Vendor,
    /// Instance name (`arm_name`, e.g. "left_arm").
    pub arm_name: String,
    /// Controller IP (`ip`, Realman).
    pub ip: IpAddr,
    /// Controller TCP port (`port`, Realman).
    pub port: u16,
    /// Local IP the state push is sent to (`udp_ip`, Realman).
    pub udp_ip: Ipv4Addr,
    /// Local UDP port the state push is sent to (`udp_port`, Realman; 0 = any free port).
    pub udp_port: u16,
    /// Push period in units of 5 ms (`udp_cycle`, Realman).
    pub udp_cycle: u32,
    /// Whether a gripper is fitted and should be read (`enable_gripper`, default false).
    pub enable_gripper: bool,
    /// SocketCAN interface (`can_interface`, Piper, default "can0"); with `socketcand`, the
    /// bus name opened on the server.
    pub can_interface: String,
    /// A socketcand server (`socketcand`, Piper, `HOST:PORT`) to reach the CAN bus through
    /// instead of a local SocketCAN interface; `None` = SocketCAN.
    pub socketcand: Option<String>,
}

impl ArmFactoryParam {
    /// Realman parameters with the controller's defaults (push to `udp_ip`:8089 every 5 ms).
    pub fn realman(arm_name: &str, ip: IpAddr, port: u16, udp_ip: Ipv4Addr) -> Self {
        Self {
            arm_type: Vendor::Realman,
            arm_name: arm_name.to_string(),
            ip,
            port,
            udp_ip,
            udp_port: 8089,
            udp_cycle: 1,
            enable_gripper: false,
            can_interface: DEFAULT_CAN_INTERFACE.to_string(),
            socketcand: None,
        }
    }

    /// Piper parameters for the CAN interface `can_interface`.
    pub fn piper(arm_name: &str, can_interface: &str) -> Self {
        Self {
            arm_type: Vendor::Piper,
            arm_name: arm_name.to_string(),
            ip: IpAddr::V4(Ipv4Addr::UNSPECIFIED),
            port: 0,
            udp_ip: Ipv4Addr::UNSPECIFIED,
            udp_port: 0,
            udp_cycle: 1,
            enable_gripper: false,
            can_interface: can_interface.to_string(),
            socketcand: None,
        }
    }

    /// Piper parameters for the bus `bus_name` of the socketcand server at `addr`
    /// (`HOST:PORT`).
    pub fn piper_socketcand(arm_name: &str, addr: &str, bus_name: &str) -> Self {
        Self {
            socketcand: Some(addr.to_string()),
            ..Self::piper(arm_name, bus_name)
        }
    }

    /// Validates string key/value pairs (the API's dictionary form). Realman needs `ip`,
    /// `port`, `udp_ip`, `udp_port` and `udp_cycle`; every vendor needs `arm_type` and
    /// `arm_name`; `enable_gripper` ("true"/"false"), `can_interface` and `socketcand`
    /// (`HOST:PORT`) are optional. Keys
    /// a vendor does not use are still checked when present.
    pub fn from_map(map: &BTreeMap<String, String>) -> Result<Self, ParamError> {
        let get = |key: &'static str| map.get(key).map(String::as_str);
        let need = |key: &'static str| get(key).ok_or(ParamError::MissingKey { key });
        let arm_type: Vendor = need("arm_type")?.parse()?;
        let arm_name = need("arm_name")?;
        if arm_name.is_empty() {
            return Err(bad("arm_name", arm_name, "a non-empty name"));
        }
        let mut p = match arm_type {
            Vendor::Realman => Self::realman(
                arm_name,
                parse_ip(need("ip")?)?,
                parse_port("port", need("port")?, 1)?,
                parse_ipv4(need("udp_ip")?)?,
            ),
            Vendor::Piper => Self::piper(arm_name, DEFAULT_CAN_INTERFACE),
        };
        if arm_type == Vendor::Realman {
            p.udp_port = parse_port("udp_port", need("udp_port")?, 0)?;
            p.udp_cycle = parse_cycle(need("udp_cycle")?)?;
        } else {
            // Optional for Piper, but a malformed value is still an error.
            if let Some(v) = get("ip") {
                p.ip = parse_ip(v)?;
            }
            if let Some(v) = get("port") {
                p.port = parse_port("port", v, 0)?;
            }
            if let Some(v) = get("udp_ip") {
                p.udp_ip = parse_ipv4(v)?;
            }
            if let Some(v) = get("udp_port") {
                p.udp_port = parse_port("udp_port", v, 0)?;
            }
            if let Some(v) = get("udp_cycle") {
                p.udp_cycle = parse_cycle(v)?;
            }
        }
        if let Some(v) = get("enable_gripper") {
            p.enable_gripper = parse_bool(v)?;
        }
        if let Some(v) = get("can_interface") {
            if v.is_empty() {
                return Err(bad("can_interface", v, "an interface name"));
            }
            p.can_interface = v.to_string();
        }
        if let Some(v) = get("socketcand") {
            p.socketcand = Some(parse_host_port(v)?);
        }
        Ok(p)
    }

    /// The Realman push period in milliseconds (`udp_cycle` × 5).
    pub fn push_period_ms(&self) -> u32 {
        self.udp_cycle * 5
    }
}

fn bad(key: &'static str, value: &str, expected: &'static str) -> ParamError {
    ParamError::BadValue {
        key,
        value: value.to_string(),
        expected,
    }
}

fn parse_ip(v: &str) -> Result<IpAddr, ParamError> {
    v.trim().parse().map_err(|_| bad("ip", v, "an IP address"))
}

fn parse_ipv4(v: &str) -> Result<Ipv4Addr, ParamError> {
    v.trim()
        .parse()
        .map_err(|_| bad("udp_ip", v, "an IPv4 address"))
}

fn parse_port(key: &'static str, v: &str, min: u16) -> Result<u16, ParamError> {
    let n: i64 = v.trim().parse().map_err(|_| bad(key, v, "an integer"))?;
    if n < i64::from(min) || n > 65535 {
        return Err(ParamError::OutOfRange {
            key,
            value: v.to_string(),
            range: if min == 0 { "0..=65535" } else { "1..=65535" },
        });
    }
    Ok(n as u16)
}

/// The controller takes periods up to 100 s; 20 000 cycles of 5 ms.
fn parse_cycle(v: &str) -> Result<u32, ParamError> {
    let n: i64 = v
        .trim()
        .parse()
        .map_err(|_| bad("udp_cycle", v, "an integer"))?;
    if !(1..=20_000).contains(&n) {
        return Err(ParamError::OutOfRange {
            key: "udp_cycle",
            value: v.to_string(),
            range: "1..=20000",
        });
    }
    Ok(n as u32)
}

/// `HOST:PORT` with a port 1–65535 (the host is resolved when connecting).
fn parse_host_port(v: &str) -> Result<String, ParamError> {
    let text = v.trim();
    let Some((host, port)) = text.rsplit_once(':') else {
        return Err(bad("socketcand", v, "HOST:PORT"));
    };
    if host.is_empty() {
        return Err(bad("socketcand", v, "HOST:PORT"));
    }
    parse_port("socketcand", port, 1)?;
    Ok(text.to_string())
}

fn parse_bool(v: &str) -> Result<bool, ParamError> {
    match v.trim().to_ascii_lowercase().as_str() {
        "true" | "1" => Ok(true),
        "false" | "0" => Ok(false),
        _ => Err(bad("enable_gripper", v, "true or false")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn realman_map() -> BTreeMap<String, String> {
        [
            ("arm_type", "realman"),
            ("arm_name", "left_arm"),
            ("ip", "192.168.1.18"),
            ("port", "8080"),
            ("udp_ip", "192.168.1.102"),
            ("udp_port", "8089"),
            ("udp_cycle", "4"),
            ("enable_gripper", "true"),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
    }

    #[test]
    fn a_complete_realman_map_parses_every_field() {
        let p = ArmFactoryParam::from_map(&realman_map()).unwrap();
        assert_eq!(p.arm_type, Vendor::Realman);
        assert_eq!(p.arm_name, "left_arm");
        assert_eq!(p.ip, "192.168.1.18".parse::<IpAddr>().unwrap());
        assert_eq!((p.port, p.udp_port, p.udp_cycle), (8080, 8089, 4));
        assert_eq!(p.udp_ip, Ipv4Addr::new(192, 168, 1, 102));
        assert!(p.enable_gripper);
        assert_eq!(p.push_period_ms(), 20);
    }

    #[test]
    fn each_missing_realman_key_is_named() {
        for key in [
            "arm_type",
            "arm_name",
            "ip",
            "port",
            "udp_ip",
            "udp_port",
            "udp_cycle",
        ] {
            let mut m = realman_map();
            m.remove(key);
            let e = ArmFactoryParam::from_map(&m).unwrap_err();
            assert_eq!(e, ParamError::MissingKey { key }, "{key}");
            assert_eq!(e.code(), AbcErrorCode::ParamError);
            assert!(ArmError::from(e).message.contains(key));
        }
        let mut m = realman_map();
        m.remove("enable_gripper");
        assert!(!ArmFactoryParam::from_map(&m).unwrap().enable_gripper);
    }

    #[test]
    fn malformed_values_name_key_and_value() {
        for (key, value) in [
            ("ip", "192.168.1"),
            ("port", "80a"),
            ("udp_ip", "::1"),
            ("udp_port", ""),
            ("udp_cycle", "1.5"),
            ("enable_gripper", "yes"),
            ("arm_name", ""),
        ] {
            let mut m = realman_map();
            m.insert(key.to_string(), value.to_string());
            let e = ArmFactoryParam::from_map(&m).unwrap_err();
            let text = e.to_string();
            assert!(matches!(e, ParamError::BadValue { .. }), "{key}: {e:?}");
            assert!(
                text.contains(key) && text.contains(&format!("{value:?}")),
                "{text}"
            );
        }
    }

    #[test]
    fn ranges_are_checked() {
        for (key, value) in [
            ("port", "0"),
            ("port", "65536"),
            ("udp_port", "-1"),
            ("udp_cycle", "0"),
        ] {
            let mut m = realman_map();
            m.insert(key.to_string(), value.to_string());
            let e = ArmFactoryParam::from_map(&m).unwrap_err();
            assert_eq!(e.code(), AbcErrorCode::ParamOutOfRange, "{key}={value}");
        }
        let mut m = realman_map();
        m.insert("udp_port".into(), "0".into());
        assert_eq!(ArmFactoryParam::from_map(&m).unwrap().udp_port, 0);
    }

    #[test]
    fn unknown_vendors_are_an_invalid_argument() {
        let mut m = realman_map();
        m.insert("arm_type".into(), "ur5".into());
        let e = ArmFactoryParam::from_map(&m).unwrap_err();
        assert_eq!(e.code(), AbcErrorCode::InvalidArgument);
        assert!(e.to_string().contains("ur5"));
    }

    #[test]
    fn piper_needs_only_type_and_name() {
        let m: BTreeMap<String, String> = [("arm_type", "piper"), ("arm_name", "right")]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        let p = ArmFactoryParam::from_map(&m).unwrap();
        assert_eq!(p.can_interface, DEFAULT_CAN_INTERFACE);
        let mut m2 = m.clone();
        m2.insert("can_interface".into(), "vxcan0".into());
        assert_eq!(
            ArmFactoryParam::from_map(&m2).unwrap().can_interface,
            "vxcan0"
        );
        let mut m3 = m.clone();
        m3.insert("port".into(), "x".into());
        assert!(ArmFactoryParam::from_map(&m3).is_err());
        assert_eq!(ArmFactoryParam::from_map(&m).unwrap().socketcand, None);
    }

    #[test]
    fn socketcand_takes_host_and_port() {
        let mut m: BTreeMap<String, String> = [("arm_type", "piper"), ("arm_name", "right")]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        m.insert("socketcand".into(), "127.0.0.1:29536".into());
        let p = ArmFactoryParam::from_map(&m).unwrap();
        assert_eq!(p.socketcand.as_deref(), Some("127.0.0.1:29536"));
        assert_eq!(p.can_interface, DEFAULT_CAN_INTERFACE);
        for (value, code) in [
            ("127.0.0.1", AbcErrorCode::ParamError),
            (":29536", AbcErrorCode::ParamError),
            ("host:port", AbcErrorCode::ParamError),
            ("localhost:0", AbcErrorCode::ParamOutOfRange),
        ] {
            m.insert("socketcand".into(), value.into());
            let e = ArmFactoryParam::from_map(&m).unwrap_err();
            assert_eq!(e.code(), code, "{value}: {e}");
            assert!(e.to_string().contains("socketcand"), "{e}");
        }
    }
}
