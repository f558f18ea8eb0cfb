//! Trajectory generation for the MOVE modes: a synchronised trapezoidal joint-space move
//! (MOVE J, MOVE P) and a time-scaled path through joint-space waypoints (MOVE L, MOVE C).
//!
//! Both are generated online, one 1 ms step at a time, so a new target can replace the old one
//! mid-motion without a velocity jump.

/// One-dimensional online trapezoid: accelerate at `a`, cruise at `v`, brake so as to stop on
/// the target. Returns the new (position, velocity).
fn trapezoid_step(pos: f64, vel: f64, target: f64, v_max: f64, a_max: f64, dt: f64) -> (f64, f64) {
    let e = target - pos;
    if a_max <= 0.0 || v_max <= 0.0 {
        return (pos, 0.0);
    }
    // Reached: close enough that one step of braking stops on the target.
    if e.abs() <= a_max * dt * dt && vel.abs() <= a_max * dt {
        return (target, 0.0);
    }
    // Speed from which braking at a_max stops exactly on the target, accounting for the
    // discrete step (v·dt of travel happens before the next decision).
    let brake = (a_max * dt).mul_add(
        -0.5,
        (2.0 * a_max * e.abs() + (0.5 * a_max * dt).powi(2)).sqrt(),
    );
    let goal = e.signum() * v_max.min(brake.max(0.0));
    let dv = (goal - vel).clamp(-a_max * dt, a_max * dt);
    let new_vel = vel + dv;
    let mut new_pos = pos + new_vel * dt;
    // Never step past the target.
    if (target - new_pos).signum() != e.signum() && (target - new_pos) != 0.0 {
        new_pos = target;
        return (new_pos, 0.0);
    }
    (new_pos, new_vel)
}

/// Duration of a rest-to-rest trapezoid over `d` with limits `v`, `a`, s.
pub fn trapezoid_duration_s(d: f64, v: f64, a: f64) -> f64 {
    let d = d.abs();
    if d == 0.0 || v <= 0.0 || a <= 0.0 {
        return 0.0;
    }
    if d >= v * v / a {
        d / v + v / a
    } else {
        2.0 * (d / a).sqrt()
    }
}

/// A synchronised joint-space move: every joint starts and ends together.
#[derive(Debug, Clone)]
pub struct JointMove {
    target: [f64; 6],
    v_max: [f64; 6],
    a_max: [f64; 6],
    q: [f64; 6],
    v: [f64; 6],
}

impl JointMove {
    /// Plan from reference state (`q`, `v`) to `target` with per-joint limits (rad/s, rad/s²).
    ///
    /// The joint whose own trapezoid takes longest sets the duration; the others get their
    /// velocity and acceleration scaled by their distance ratio so they finish with it.
    pub fn new(
        q: [f64; 6],
        v: [f64; 6],
        target: [f64; 6],
        v_lim: [f64; 6],
        a_lim: [f64; 6],
    ) -> Self {
        let mut crit = 0;
        let mut crit_t = -1.0;
        for j in 0..6 {
            let t = trapezoid_duration_s(target[j] - q[j], v_lim[j], a_lim[j]);
            if t > crit_t {
                crit_t = t;
                crit = j;
            }
        }
        let d_crit = (target[crit] - q[crit]).abs();
        let mut v_max = v_lim;
        let mut a_max = a_lim;
        if d_crit > 0.0 {
            for j in 0..6 {
                let ratio = (target[j] - q[j]).abs() / d_crit;
                // A joint that is already moving keeps at least a small budget to brake.
                v_max[j] = (v_lim[crit] * ratio).min(v_lim[j]).max(1e-6);
                a_max[j] = (a_lim[crit] * ratio).min(a_lim[j]).max(a_lim[j] * 0.05);
            }
        }
        Self {
            target,
            v_max,
            a_max,
            q,
            v,
        }
    }

    /// Advance by `dt` s; returns the reference (position, velocity).
    pub fn step(&mut self, dt: f64) -> ([f64; 6], [f64; 6]) {
        for j in 0..6 {
            let (q, v) = trapezoid_step(
                self.q[j],
                self.v[j],
                self.target[j],
                self.v_max[j],
                self.a_max[j],
                dt,
            );
            self.q[j] = q;
            self.v[j] = v;
        }
        (self.q, self.v)
    }

    /// True once every joint's reference rests on its target.
    pub fn done(&self) -> bool {
        (0..6).all(|j| self.q[j] == self.target[j] && self.v[j] == 0.0)
    }

    /// The target.
    pub fn target(&self) -> [f64; 6] {
        self.target
    }

    /// Current reference (position, velocity).
    pub fn reference(&self) -> ([f64; 6], [f64; 6]) {
        (self.q, self.v)
    }
}

/// A path through joint-space waypoints (from a Cartesian line or arc), timed on its
/// normalised parameter s ∈ [0, 1].
#[derive(Debug, Clone)]
pub struct PathMove {
    waypoints: Vec<[f64; 6]>,
    s: f64,
    s_dot: f64,
    s_dot_max: f64,
    s_ddot_max: f64,
}

impl PathMove {
    /// `waypoints` sampled evenly in s; `s_dot_max` / `s_ddot_max` are the path-speed limits
    /// (1/s, 1/s²) from the Cartesian limits. They are lowered further so that no joint
    /// exceeds `v_lim` / `a_lim`.
    pub fn new(
        waypoints: Vec<[f64; 6]>,
        s_dot_max: f64,
        s_ddot_max: f64,
        v_lim: [f64; 6],
        a_lim: [f64; 6],
    ) -> Self {
        let segments = waypoints.len().saturating_sub(1).max(1) as f64;
        let mut s_dot = s_dot_max;
        let mut s_ddot = s_ddot_max;
        for w in waypoints.windows(2) {
            for j in 0..6 {
                let dq_ds = (w[1][j] - w[0][j]).abs() * segments;
                if dq_ds > 1e-12 {
                    s_dot = s_dot.min(v_lim[j] / dq_ds);
                    s_ddot = s_ddot.min(a_lim[j] / dq_ds);
                }
            }
        }
        Self {
            waypoints,
            s: 0.0,
            s_dot: 0.0,
            s_dot_max: s_dot.max(1e-6),
            s_ddot_max: s_ddot.max(1e-6),
        }
    }

    /// Start moving along the path at the speed of joint velocity `v` projected onto the
    /// path's initial direction (never backwards), so a replanned path continues the motion
    /// instead of restarting from rest.
    pub fn with_initial_velocity(mut self, v: [f64; 6]) -> Self {
        let (_, dq_ds) = self.at(0.0);
        let along: f64 = (0..6).map(|j| v[j] * dq_ds[j]).sum();
        let norm2: f64 = dq_ds.iter().map(|d| d * d).sum();
        if norm2 > 1e-18 && along.is_finite() {
            self.s_dot = (along / norm2).max(0.0);
        }
        self
    }

    fn at(&self, s: f64) -> ([f64; 6], [f64; 6]) {
        let n = self.waypoints.len();
        if n == 0 {
            return ([0.0; 6], [0.0; 6]);
        }
        if n == 1 {
            return (self.waypoints[0], [0.0; 6]);
        }
        let segments = (n - 1) as f64;
        if s >= 1.0 {
            let mut dq_ds = [0.0; 6];
            for (j, d) in dq_ds.iter_mut().enumerate() {
                *d = (self.waypoints[n - 1][j] - self.waypoints[n - 2][j]) * segments;
            }
            return (self.waypoints[n - 1], dq_ds);
        }
        let x = (s.max(0.0) * segments).min(segments - 1e-9);
        let i = x.floor() as usize;
        let f = x - i as f64;
        let (a, b) = (self.waypoints[i], self.waypoints[i + 1]);
        let mut q = [0.0; 6];
        let mut dq_ds = [0.0; 6];
        for j in 0..6 {
            q[j] = a[j] + (b[j] - a[j]) * f;
            dq_ds[j] = (b[j] - a[j]) * segments;
        }
        (q, dq_ds)
    }

    /// Advance by `dt` s; returns the reference (position, velocity).
    pub fn step(&mut self, dt: f64) -> ([f64; 6], [f64; 6]) {
        let (s, s_dot) =
            trapezoid_step(self.s, self.s_dot, 1.0, self.s_dot_max, self.s_ddot_max, dt);
        self.s = s;
        self.s_dot = s_dot;
        self.reference()
    }

    /// Current reference (position, velocity).
    pub fn reference(&self) -> ([f64; 6], [f64; 6]) {
        let (q, dq_ds) = self.at(self.s);
        let mut v = [0.0; 6];
        for j in 0..6 {
            v[j] = dq_ds[j] * self.s_dot;
        }
        (q, v)
    }

    /// True once the path's end is reached.
    pub fn done(&self) -> bool {
        self.s >= 1.0 && self.s_dot == 0.0
    }

    /// The final waypoint.
    pub fn target(&self) -> [f64; 6] {
        self.waypoints.last().copied().unwrap_or([0.0; 6])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(m: &mut JointMove) -> f64 {
        let mut t = 0.0;
        while !m.done() && t < 100.0 {
            m.step(0.001);
            t += 0.001;
        }
        t
    }

    #[test]
    fn trapezoid_time_matches_formula() {
        let target = [std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0, 0.0, 0.0];
        let mut m = JointMove::new([0.0; 6], [0.0; 6], target, [1.5; 6], [5.0; 6]);
        let t = run(&mut m);
        let expected = trapezoid_duration_s(target[0], 1.5, 5.0);
        assert!((t - expected).abs() < 0.01 * expected, "{t} vs {expected}");
        assert_eq!(m.reference().0, target);
    }

    #[test]
    fn joints_finish_together_and_respect_limits() {
        let target = [1.0, -0.5, 0.25, 0.0, 2.0, -0.1];
        let mut m = JointMove::new([0.0; 6], [0.0; 6], target, [3.0; 6], [5.0; 6]);
        let mut last = [0.0; 6];
        let mut t = 0.0;
        let mut finish = [0.0f64; 6];
        while !m.done() && t < 100.0 {
            let (q, v) = m.step(0.001);
            t += 0.001;
            for j in 0..6 {
                assert!(v[j].abs() <= 3.0 + 1e-9);
                // The final snap onto the target may drop the last sliver of speed at once.
                assert!((v[j] - last[j]).abs() <= 2.0 * 5.0 * 0.001 + 1e-9);
                if q[j] != target[j] {
                    finish[j] = t;
                }
            }
            last = v;
        }
        let longest = trapezoid_duration_s(2.0, 3.0, 5.0);
        assert!((t - longest).abs() < 0.02 * longest);
        for j in [0, 1, 2, 4, 5] {
            assert!((finish[j] - finish[4]).abs() < 0.05, "{finish:?}");
        }
    }

    #[test]
    fn path_reaches_the_end() {
        let wps: Vec<[f64; 6]> = (0..=10).map(|i| [i as f64 * 0.1; 6]).collect();
        let mut p = PathMove::new(wps, 10.0, 10.0, [0.5; 6], [5.0; 6]);
        let mut t = 0.0;
        while !p.done() && t < 100.0 {
            let (_, v) = p.step(0.001);
            assert!(v.iter().all(|x| x.abs() <= 0.5 + 1e-9));
            t += 0.001;
        }
        assert_eq!(p.reference().0, [1.0; 6]);
        assert!(t > 2.0 && t < 2.5, "{t}");
    }
}
