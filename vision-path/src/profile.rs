//! The speed profile along one piece: accelerate at `a`, cruise, decelerate at `a`
//! (a trapezoid, or a triangle when the piece is too short to reach the cruise speed).

/// A profile over the path parameter `s` (machine units), time from its start (seconds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Profile {
    s0: f64,
    v0: f64,
    vp: f64,
    v1: f64,
    a: f64,
    t1: f64,
    t2: f64,
    t3: f64,
    d1: f64,
    s_end: f64,
}

impl Profile {
    /// The fastest profile over `[0, len]` entering at `v0`, leaving at `v1`, never faster
    /// than `v_cap` and never accelerating harder than `a` (units/s, units/s²). The planner
    /// guarantees `|v1² − v0²| ≤ 2·a·len`; rounding beyond it is absorbed.
    pub(crate) fn trapezoid(len: f64, v0: f64, v1: f64, v_cap: f64, a: f64) -> Profile {
        let peak2 = (v_cap * v_cap).min(a * len + 0.5 * (v0 * v0 + v1 * v1));
        let vp = peak2.sqrt().max(v0).max(v1);
        let d1 = (vp * vp - v0 * v0) / (2.0 * a);
        let d3 = (vp * vp - v1 * v1) / (2.0 * a);
        let d2 = (len - d1 - d3).max(0.0);
        let t2 = if vp > 0.0 { d2 / vp } else { 0.0 };
        Profile { s0: 0.0, v0, vp, v1, a, t1: (vp - v0) / a, t2, t3: (vp - v1) / a, d1, s_end: len }
    }

    /// Brake at `a` from speed `v0` at `s0` towards `len`: rest before `len`, or leave it at
    /// the speed that is left.
    pub(crate) fn braking(s0: f64, v0: f64, len: f64, a: f64) -> Profile {
        let room = (len - s0).max(0.0);
        let (v1, s_end) = if v0 * v0 <= 2.0 * a * room {
            (0.0, s0 + v0 * v0 / (2.0 * a))
        } else {
            ((v0 * v0 - 2.0 * a * room).sqrt(), len)
        };
        Profile { s0, v0, vp: v0, v1, a, t1: 0.0, t2: 0.0, t3: (v0 - v1) / a, d1: 0.0, s_end }
    }

    /// Duration, seconds.
    pub(crate) fn duration(&self) -> f64 {
        self.t1 + self.t2 + self.t3
    }

    /// Speed when the profile ends, units/s.
    pub(crate) fn end_speed(&self) -> f64 {
        self.v1
    }

    /// Parameter where the profile ends, machine units.
    pub(crate) fn end_s(&self) -> f64 {
        self.s_end
    }

    /// `(s, ṡ)` at time `tau` after the start (clamped to the profile).
    pub(crate) fn at(&self, tau: f64) -> (f64, f64) {
        let total = self.duration();
        let (s, v) = if tau <= 0.0 {
            (self.s0, self.v0)
        } else if tau < self.t1 {
            (self.s0 + self.v0 * tau + 0.5 * self.a * tau * tau, self.v0 + self.a * tau)
        } else if tau < self.t1 + self.t2 {
            (self.s0 + self.d1 + self.vp * (tau - self.t1), self.vp)
        } else if tau < total {
            let tr = total - tau;
            (self.s_end - (self.v1 * tr + 0.5 * self.a * tr * tr), self.v1 + self.a * tr)
        } else {
            (self.s_end, self.v1)
        };
        (s.clamp(self.s0, self.s_end), v)
    }
}

#[cfg(test)]
#[expect(clippy::float_cmp, reason = "tests compare exact values")]
mod tests {
    use super::*;

    #[test]
    fn a_long_move_from_rest_to_rest_is_the_analytic_trapezoid() {
        // 100 units at cap 50 units/s, a = 1000: 0.05 s up, 1.25 units each ramp.
        let p = Profile::trapezoid(100.0, 0.0, 0.0, 50.0, 1000.0);
        assert!((p.duration() - (0.05 + 97.5 / 50.0 + 0.05)).abs() < 1e-12);
        let (s, v) = p.at(0.05);
        assert!((s - 1.25).abs() < 1e-12 && (v - 50.0).abs() < 1e-12);
        assert_eq!(p.at(p.duration()), (100.0, 0.0));
        assert_eq!(p.at(p.duration() + 1.0), (100.0, 0.0));
    }

    #[test]
    fn a_short_move_is_a_triangle() {
        let p = Profile::trapezoid(1.0, 0.0, 0.0, 1e9, 100.0);
        // Peak sqrt(a·L) = 10 at half-way, after 0.1 s.
        assert!((p.duration() - 0.2).abs() < 1e-12);
        let (s, v) = p.at(0.1);
        assert!((s - 0.5).abs() < 1e-12 && (v - 10.0).abs() < 1e-12);
    }

    #[test]
    fn entry_and_exit_speeds_are_kept() {
        let p = Profile::trapezoid(10.0, 3.0, 7.0, 8.0, 50.0);
        assert_eq!(p.at(0.0).1, 3.0);
        assert!((p.at(p.duration() - 1e-12).1 - 7.0).abs() < 1e-9);
        assert_eq!(p.end_speed(), 7.0);
    }

    #[test]
    fn braking_stops_inside_or_leaves_with_what_is_left() {
        let p = Profile::braking(2.0, 10.0, 100.0, 50.0);
        assert_eq!(p.end_speed(), 0.0);
        assert!((p.end_s() - 3.0).abs() < 1e-12);
        assert!((p.duration() - 0.2).abs() < 1e-12);
        let q = Profile::braking(2.0, 10.0, 2.5, 50.0);
        assert!((q.end_speed() - 50f64.sqrt()).abs() < 1e-12);
        assert_eq!(q.end_s(), 2.5);
    }
}
