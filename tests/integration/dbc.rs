//! `docs/dbc/piper.dbc` is generated from `armhil::interop`'s signal table, and that table
//! agrees with the driver's codec byte for byte.

use armhil::interop::{piper_dbc, piper_messages, probe_field};
use bus::CanFrame;
use serde_json::Value;

const DBC_PATH: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/dbc/piper.dbc");

#[test]
fn dbc_file_matches_the_generator() {
    let generated = piper_dbc();
    if std::env::var_os("ARMHIL_BLESS").is_some() {
        std::fs::write(DBC_PATH, &generated).expect("write the DBC");
    }
    let stored = std::fs::read_to_string(DBC_PATH).expect("docs/dbc/piper.dbc exists");
    assert!(
        stored == generated,
        "docs/dbc/piper.dbc is stale: regenerate with ARMHIL_BLESS=1 cargo test -p armhil --test integration dbc"
    );
}

/// Raw test values of an `bits`-wide field, extremes included.
fn samples(bits: u8, signed: bool) -> Vec<i64> {
    let (lo, hi) = if signed {
        (-(1i64 << (bits - 1)), (1i64 << (bits - 1)) - 1)
    } else {
        (0, (1i64 << bits) - 1)
    };
    let mut v = vec![lo, hi, 0, 1, hi / 3, lo / 7];
    v.retain(|x| (lo..=hi).contains(x));
    v
}

#[test]
fn every_signal_sits_where_the_driver_codec_reads_it() {
    let mut checked = 0;
    for message in piper_messages() {
        for signal in &message.signals {
            for raw in samples(signal.bits, signal.signed) {
                // Fill the other bytes with a pattern so a wrong offset shows.
                let mut data = [0xA5u8; 8];
                let bytes = (raw as u64).to_be_bytes();
                let n = usize::from(signal.bits / 8);
                data[signal.byte..signal.byte + n].copy_from_slice(&bytes[8 - n..]);
                let frame = CanFrame::standard(message.id, &data).expect("valid frame");
                let decoded = driver::piper::codec::decode(&frame)
                    .expect("driver decodes it")
                    .unwrap_or_else(|| panic!("driver ignores {:#x}", message.id));
                let json = serde_json::to_value(decoded).expect("serializes");
                let value = probe_field(&json, signal.field)
                    .unwrap_or_else(|| panic!("{}: no field {}", message.name, signal.field));
                let got = match value {
                    Value::Number(n) => n.as_i64(),
                    // An enum: a label for defined codes, `{"Unknown": raw}` otherwise; only
                    // 8-bit fields may be enums, and a label means the driver read this byte.
                    Value::String(_) => Some(raw),
                    Value::Object(map) => map.get("Unknown").and_then(Value::as_i64),
                    _ => None,
                };
                assert_eq!(
                    got,
                    Some(raw),
                    "{} {}: raw {raw} decoded as {value}",
                    message.name,
                    signal.name
                );
                checked += 1;
            }
        }
    }
    assert!(checked > 300, "only {checked} checks");
}

#[test]
fn dbc_has_value_tables_for_the_status_enums() {
    let dbc = piper_dbc();
    assert!(dbc.contains("VAL_ 673 ctrl_mode "), "{dbc}");
    assert!(dbc.contains("VAL_ 673 arm_status "));
    assert!(dbc.contains(" SG_ J1_angle : 7|32@0- (0.001,0)"));
    assert!(dbc.contains("BO_ 593 DriverHighSpeed1: 8 Piper"));
}
