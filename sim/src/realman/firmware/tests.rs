//! Unit tests of the firmware's helpers, one module per file they test (the behaviour seen
//! through the wire is tested in sim/tests/realman/firmware.rs).

mod cmd_ioports {
    use super::super::cmd_ioports::*;

    #[test]
    fn version_codes_are_one_hex_digit_per_number() {
        assert_eq!(version_code("V1.7.0"), 0x0170);
        assert_eq!(version_code("V3.0.9"), 0x0309);
        assert_eq!((model_byte("RM65-B") << 16) | 0x0309, 0x6B0309);
    }
}

mod peripherals {
    use super::super::peripherals::*;

    #[test]
    fn registers_answer_only_on_a_port_in_modbus_mode() {
        let mut p = Peripherals::default();
        assert!(!p.write(0, 1, 10, &[0x12, 0x34]));
        assert_eq!(p.read(0, 1, 10), None);
        assert!(p.open(0, 115_200, 2));
        assert!(p.write(0, 1, 10, &[0x12, 0x34, 0xFF, 0xFE]));
        assert_eq!(p.read(0, 1, 10), Some(0x1234));
        assert_eq!(p.read(0, 1, 11), Some(-2));
        assert_eq!(
            p.read(0, 2, 10),
            Some(0),
            "another device has its own registers"
        );
        assert!(p.close(0));
        assert_eq!(p.read(0, 1, 10), None);
    }

    #[test]
    fn bad_modbus_arguments_are_refused() {
        let mut p = Peripherals::default();
        assert!(!p.open(3, 115_200, 1), "port 3 is Modbus TCP, not RTU");
        assert!(!p.open(0, 12_345, 1));
        assert!(p.open(1, 9600, 0));
        assert_eq!(p.ports[&1].timeout_100ms, 1, "0 is taken as 1");
        assert!(p.tool_port_in_modbus());
        assert!(!p.write(1, 1, 0, &[1]), "odd byte count");
        assert!(!p.write(1, 1, 0, &[0; 22]), "11 registers");
        assert!(
            !p.write(1, 0, 0, &[0, 1]),
            "device 0 is the broadcast address"
        );
        assert!(!p.write(1, 1, 0, &[256, 0]), "not a byte");
        assert!(
            !p.write(1, 1, 65_535, &[0, 1, 0, 2]),
            "past the last address"
        );
        assert!(!p.set_plus_mode(1000));
        assert!(p.set_plus_mode(256_000));
    }
}

mod stream {
    use super::super::stream::*;

    const LIMITS: JointLimits = JointLimits {
        min_rad: -3.0,
        max_rad: 3.0,
        speed_rad_s: 3.0,
        acc_rad_s2: 9.0,
    };

    /// Ticks until the set-point reaches `target` from 0, and the largest speed change per tick.
    fn run(tracking: Tracking, target: f64) -> (usize, f64) {
        let mut s = Stream::new(vec![target], "move_through_joint", tracking, None);
        let mut q = [0.0];
        let mut last_v = 0.0;
        let mut max_dv: f64 = 0.0;
        for tick in 1..10_000 {
            let before = q[0];
            let done = s.advance(&mut q, &[LIMITS], 0.001);
            let v = (q[0] - before) / 0.001;
            max_dv = max_dv.max((v - last_v).abs());
            last_v = v;
            if done {
                return (tick, max_dv);
            }
        }
        panic!("never arrived; at {}", q[0]);
    }

    #[test]
    fn direct_tracking_jumps_to_full_speed_and_planned_tracking_ramps() {
        let (direct_ticks, direct_dv) = run(Tracking::Direct, 1.5);
        let (planned_ticks, planned_dv) = run(Tracking::Planned, 1.5);
        // 1.5 rad at 3 rad/s: 0.5 s straight; planned adds the 2 × 1/3 s ramps' lost time.
        assert!((499..=501).contains(&direct_ticks), "{direct_ticks}");
        assert!((820..=850).contains(&planned_ticks), "{planned_ticks}");
        assert!(direct_dv > 2.9, "direct starts at full speed: {direct_dv}");
        // Planned speed changes by at most a (9 rad/s²) × 1 ms per tick, and a little landing.
        assert!(planned_dv < 0.05, "planned speed step {planned_dv}");
    }

    #[test]
    fn targets_are_clamped_to_the_joint_limits() {
        let mut s = Stream::new(vec![5.0], "move_through_joint", Tracking::Planned, None);
        let mut q = [2.9];
        for _ in 0..1000 {
            s.advance(&mut q, &[LIMITS], 0.001);
        }
        assert!((q[0] - 3.0).abs() < 1e-9, "{}", q[0]);
    }
}
