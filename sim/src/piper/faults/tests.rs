//! The fault table and `PiperFault`: names, displays, sites, ranges.

use super::*;

#[test]
fn every_kind_has_its_own_name_and_a_description() {
    for (i, a) in FaultKind::ALL.iter().enumerate() {
        assert_eq!(FaultKind::from_name(a.name()), Some(*a));
        assert!(!a.description().is_empty());
        for b in &FaultKind::ALL[i + 1..] {
            assert_ne!(a.name(), b.name());
        }
    }
    assert_eq!(FaultKind::from_name("comm_los"), None);
}

#[test]
fn display_starts_with_the_kind_name_and_lists_the_values() {
    let f = PiperFault::MotorOverTemp {
        joint: 2,
        temp_c: 90.0,
    };
    assert_eq!(f.to_string(), "motor_over_temp joint 2 90 C");
    let ntc = PiperFault::NtcOverTemp {
        board: NtcBoard::BrakeResistor,
    };
    assert_eq!(ntc.to_string(), "ntc_over_temp brake_resistor");
    assert_eq!(PiperFault::Estop.to_string(), "estop");
    assert_eq!(
        PiperFault::UnderVoltage { voltage_v: 18.5 }.to_string(),
        "under_voltage 18.5 V"
    );
}

#[test]
fn same_site_ignores_values_but_not_joints_or_boards() {
    let hot = PiperFault::DriverOverTemp {
        joint: 3,
        temp_c: 95.0,
    };
    let any = PiperFault::DriverOverTemp {
        joint: 3,
        temp_c: 0.0,
    };
    let other_joint = PiperFault::DriverOverTemp {
        joint: 4,
        temp_c: 95.0,
    };
    assert!(hot.same_site(&any));
    assert!(!hot.same_site(&other_joint));
    assert!(!hot.same_site(&PiperFault::MotorOverTemp {
        joint: 3,
        temp_c: 95.0
    }));
    let main = PiperFault::NtcOverTemp {
        board: NtcBoard::Main,
    };
    let resistor = PiperFault::NtcOverTemp {
        board: NtcBoard::BrakeResistor,
    };
    assert!(!main.same_site(&resistor));
}

#[test]
fn every_numeric_parameter_has_a_range_holding_its_default() {
    for kind in FaultKind::ALL {
        for p in kind.params() {
            if p.name == "board" {
                assert_eq!(p.range, None);
                continue;
            }
            let (min, max) = p.range.unwrap_or_else(|| panic!("{}: no range", p.name));
            assert!(
                min < max && min.is_finite() && max.is_finite(),
                "{}",
                p.name
            );
            if let Some(d) = p.default {
                assert_eq!(p.check(d), Ok(d), "{}: default outside its range", p.name);
            }
        }
    }
}

#[test]
fn absurd_values_are_refused_with_a_short_message() {
    let torque = PiperFault::ExternalTorque {
        joint: 1,
        torque_nm: 1e308,
    };
    let err = torque.check().unwrap_err();
    assert!(matches!(
        err,
        FaultError::OutOfRange {
            param: "torque_nm",
            ..
        }
    ));
    let text = err.to_string();
    assert_eq!(text, "`torque_nm` must be between -320 and 320, got 1e308");
    for fault in [
        PiperFault::ExternalTorque {
            joint: 6,
            torque_nm: -320.5,
        },
        PiperFault::MotorOverTemp {
            joint: 2,
            temp_c: 1e308,
        },
        PiperFault::DriverOverTemp {
            joint: 2,
            temp_c: f64::NAN,
        },
        PiperFault::UnderVoltage { voltage_v: -1.0 },
        PiperFault::UnderVoltage {
            voltage_v: f64::INFINITY,
        },
    ] {
        let text = fault.check().unwrap_err().to_string();
        assert!(text.len() < 80, "{text}");
    }
    assert_eq!(
        PiperFault::Stall { joint: 7 }.check(),
        Err(FaultError::NoSuchJoint { joint: 7 })
    );
}

#[test]
fn plausible_values_pass() {
    for fault in [
        PiperFault::ExternalTorque {
            joint: 1,
            torque_nm: -320.0,
        },
        PiperFault::MotorOverTemp {
            joint: 6,
            temp_c: 150.0,
        },
        PiperFault::UnderVoltage { voltage_v: 0.0 },
        PiperFault::Estop,
    ] {
        assert_eq!(fault.check(), Ok(()), "{fault}");
    }
}

#[test]
fn display_does_not_echo_hundreds_of_digits() {
    let f = PiperFault::ExternalTorque {
        joint: 1,
        torque_nm: 1e308,
    };
    assert_eq!(f.to_string(), "external_torque joint 1 1e308 Nm");
}

#[test]
fn only_faults_without_required_parameters_may_be_written_bare() {
    assert!(FaultKind::Estop.bare_ok());
    assert!(FaultKind::UnderVoltage.bare_ok());
    assert!(FaultKind::NtcOverTemp.bare_ok());
    assert!(!FaultKind::CommLoss.bare_ok());
    assert!(!FaultKind::ExternalTorque.bare_ok());
}

mod builder {
    use super::*;
    use crate::fault_args::{FaultArgError, FaultArgValue, FaultArgs};

    fn num(v: f64) -> FaultArgValue {
        FaultArgValue::Number(v)
    }

    fn text(t: &str) -> FaultArgValue {
        FaultArgValue::Text(t.to_owned())
    }

    fn refused(name: &str, args: FaultArgs) -> FaultArgError {
        build_fault(name, &args).unwrap_err()
    }

    #[test]
    fn omitted_values_take_the_table_defaults() {
        let args = FaultArgs::new().with("joint", num(2.0));
        assert_eq!(
            build_fault("motor_over_temp", &args),
            Ok(PiperFault::MotorOverTemp {
                joint: 2,
                temp_c: 90.0
            })
        );
        assert_eq!(
            build_fault("under_voltage", &FaultArgs::new()),
            Ok(PiperFault::UnderVoltage { voltage_v: 18.0 })
        );
        assert_eq!(
            build_fault("ntc_over_temp", &FaultArgs::new()),
            Ok(PiperFault::NtcOverTemp {
                board: NtcBoard::Main
            })
        );
        let resistor = FaultArgs::new().with("board", text("brake_resistor"));
        assert_eq!(
            build_fault("ntc_over_temp", &resistor),
            Ok(PiperFault::NtcOverTemp {
                board: NtcBoard::BrakeResistor
            })
        );
        assert_eq!(
            build_fault("estop", &FaultArgs::new()),
            Ok(PiperFault::Estop)
        );
    }

    #[test]
    fn every_kind_builds_from_full_arguments_and_passes_the_emulator_check() {
        for kind in FaultKind::ALL {
            let mut args = FaultArgs::new();
            for p in kind.params() {
                let value = match p.name {
                    "joint" => num(6.0),
                    "board" => text("main"),
                    _ => num(p.range.map_or(0.0, |r| r.1)),
                };
                args.push(p.name, value);
            }
            let fault = kind
                .build(&args)
                .unwrap_or_else(|e| panic!("{kind:?}: {e}"));
            assert_eq!(fault.kind(), kind);
            assert_eq!(fault.check(), Ok(()), "{fault}");
        }
    }

    #[test]
    fn bad_arguments_are_refused_with_the_scenario_wording() {
        let cases: [(&str, FaultArgs, Option<&str>, &str); 9] = [
            (
                "estop",
                FaultArgs::new().with("joint", num(1.0)),
                Some("joint"),
                "`estop` takes no `joint` (it takes: no arguments)",
            ),
            (
                "stall",
                FaultArgs::new().with("temp_c", num(1.0)),
                Some("temp_c"),
                "`stall` takes no `temp_c` (it takes: joint)",
            ),
            ("stall", FaultArgs::new(), None, "`stall` needs `joint`"),
            (
                "stall",
                FaultArgs::new().with("joint", num(7.0)),
                Some("joint"),
                "`joint`: joint index 7 out of range, expected 1..=6",
            ),
            (
                "stall",
                FaultArgs::new().with("joint", num(2.5)),
                Some("joint"),
                "`joint`: joint index 2.5 out of range, expected 1..=6",
            ),
            (
                "external_torque",
                FaultArgs::new().with("joint", num(1.0)),
                None,
                "`external_torque` needs `torque_nm`",
            ),
            (
                "external_torque",
                FaultArgs::new()
                    .with("joint", num(1.0))
                    .with("torque_nm", num(1e308)),
                Some("torque_nm"),
                "`torque_nm` must be between -320 and 320, got 1e308",
            ),
            (
                "motor_over_temp",
                FaultArgs::new()
                    .with("joint", num(1.0))
                    .with("temp_c", num(f64::NAN)),
                Some("temp_c"),
                "`temp_c` must be a finite number",
            ),
            (
                "ntc_over_temp",
                FaultArgs::new().with("board", text("aux")),
                Some("board"),
                "`board`: unknown value `aux`; expected one of: main, brake_resistor",
            ),
        ];
        for (name, args, arg, message) in cases {
            let err = refused(name, args);
            assert_eq!(err.message, message);
            assert_eq!(err.arg.as_deref(), arg, "{message}");
        }
    }

    #[test]
    fn a_negative_voltage_is_refused_not_clamped() {
        let err = refused(
            "under_voltage",
            FaultArgs::new().with("voltage_v", num(-1.0)),
        );
        assert_eq!(err.message, "`voltage_v` must be between 0 and 60, got -1");
    }

    #[test]
    fn unknown_names_and_long_words_give_short_messages() {
        let err = refused("comm_los", FaultArgs::new());
        assert_eq!(err.arg, None);
        assert!(
            err.message
                .starts_with("no Piper fault `comm_los`; known: comm_loss, "),
            "{}",
            err.message
        );
        let blob = "x".repeat(300);
        let err = refused(
            "external_torque",
            FaultArgs::new()
                .with("joint", num(1.0))
                .with("torque_nm", text(&blob)),
        );
        assert!(err.message.len() < 100, "{}", err.message);
        assert!(err
            .message
            .starts_with("`torque_nm` must be a number, got `xxx"));
    }

    #[test]
    fn clearing_needs_the_site_but_not_the_values() {
        let joint = FaultArgs::new().with("joint", num(3.0));
        assert_eq!(
            FaultKind::ExternalTorque.build_to_clear(&joint),
            Ok(PiperFault::ExternalTorque {
                joint: 3,
                torque_nm: 0.0
            })
        );
        let absurd = joint.clone().with("temp_c", num(1e308));
        let hot = FaultKind::DriverOverTemp.build_to_clear(&absurd).unwrap();
        assert!(hot.same_site(&PiperFault::DriverOverTemp {
            joint: 3,
            temp_c: 95.0
        }));
        assert!(FaultKind::Stall.build_to_clear(&FaultArgs::new()).is_err());
        assert!(FaultKind::Stall.build_to_clear(&absurd).is_err());
    }
}

#[test]
fn the_name_tables_match_the_kinds() {
    use strum::IntoEnumIterator;
    assert!(FaultKind::iter().eq(FaultKind::ALL));
    assert!(NtcBoard::iter().eq(NtcBoard::ALL));
    assert_eq!(
        FaultKind::from_name("ntc_over_temp"),
        Some(FaultKind::NtcOverTemp)
    );
    assert_eq!(FaultKind::Estop.name(), "estop");
    assert_eq!(
        NtcBoard::from_name("brake_resistor"),
        Some(NtcBoard::BrakeResistor)
    );
    assert_eq!(
        BOARD.words,
        NtcBoard::ALL.map(NtcBoard::name).as_slice(),
        "the board parameter lists every board, the default first"
    );
}
