use super::*;

#[test]
fn profile_is_continuous_and_ends_at_one() {
    for (v, a) in [(0.5, 2.0), (5.0, 2.0), (1.0, 1.0)] {
        let p = Profile::new(v, a);
        let mut last = 0.0;
        let n = 1000;
        for i in 0..=n {
            let (s, ds) = p.at(p.total_s * i as f64 / n as f64);
            assert!(s >= last - 1e-12 && ds <= v + 1e-9, "{v} {a}");
            assert!((s - last).abs() < 2.0 / n as f64 * v.max(1.0) + 1e-9);
            last = s;
        }
        assert!((last - 1.0).abs() < 1e-12);
    }
}
