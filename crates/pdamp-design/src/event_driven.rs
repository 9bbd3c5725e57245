//! Event-driven reference solution of one particle in a container moved as
//! $x_c = X\sin(\Omega t)$ without gravity: free flight between the walls, instantaneous impacts
//! with Newton restitution ε, and for ε = 0 the particle rides on the wall while the wall pushes
//! it (collect-and-collide limit, [D Sect. 5.1.3, 6.1.3]). Impact times are found by bracketing on
//! a fine scan and bisection to round-off, independently of the DEM.

use std::f64::consts::PI;

/// The idealised single-particle damper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SingleParticleDamper {
    /// Free travel of the particle centre between the two walls, h = L − 2r, m.
    pub clearance_m: f64,
    /// Container amplitude X, m.
    pub amplitude_m: f64,
    /// Excitation frequency f, Hz.
    pub frequency_hz: f64,
    /// Newton coefficient of restitution of the wall impacts.
    pub restitution: f64,
}

/// Result of [`SingleParticleDamper::simulate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventDrivenResult {
    /// Dissipated energy per cycle per kg of particle mass, J/kg.
    pub dissipated_per_cycle_j_kg: f64,
    /// Effective loss factor η̄ = Ẽ/(2π · ½ m V²) [D Eq. 3.15].
    pub effective_loss_factor: f64,
    /// Impacts per evaluated cycle.
    pub impacts_per_cycle: f64,
}

#[derive(Debug, Clone, Copy)]
enum State {
    /// Free flight from (t0, z0) with velocity u.
    Free { t0: f64, z0: f64, u: f64 },
    /// Riding on wall `side` (+1 upper, −1 lower) until the wall stops pushing.
    Stuck { side: f64 },
}

impl SingleParticleDamper {
    fn omega(&self) -> f64 {
        2.0 * PI * self.frequency_hz
    }
    fn xc(&self, t: f64) -> f64 {
        self.amplitude_m * (self.omega() * t).sin()
    }
    fn vc(&self, t: f64) -> f64 {
        self.amplitude_m * self.omega() * (self.omega() * t).cos()
    }
    fn ac(&self, t: f64) -> f64 {
        -self.amplitude_m * self.omega().powi(2) * (self.omega() * t).sin()
    }

    /// Earliest time after `t0` at which the free particle reaches a wall, with the wall side.
    fn next_impact(&self, t0: f64, z0: f64, u: f64) -> (f64, f64) {
        let s = 0.5 * self.clearance_m;
        let gap = |t: f64, side: f64| side * (z0 + u * (t - t0) - self.xc(t)) - s; // ≥ 0: contact
        let h = 1.0 / (self.frequency_hz * 4000.0);
        let mut a = t0;
        // Skip the start point itself (the particle may just have left a wall).
        let eps = 1e-12 / self.frequency_hz;
        loop {
            let b = a + h;
            for side in [1.0, -1.0] {
                let ga = gap(a.max(t0 + eps), side);
                let gb = gap(b, side);
                if ga < 0.0 && gb >= 0.0 {
                    let (mut lo, mut hi) = (a.max(t0 + eps), b);
                    for _ in 0..200 {
                        let m = 0.5 * (lo + hi);
                        if gap(m, side) >= 0.0 {
                            hi = m;
                        } else {
                            lo = m;
                        }
                        if hi - lo < 1e-15 * hi.abs().max(1.0) {
                            break;
                        }
                    }
                    return (hi, side);
                }
            }
            a = b;
        }
    }

    /// Simulates from the particle at rest at `start_m` from the container centre at t = 0 (the
    /// container starts at x_c = 0 with velocity V), drops `transient_cycles` and evaluates
    /// `cycles` cycles.
    pub fn simulate(&self, start_m: f64, transient_cycles: u32, cycles: u32) -> EventDrivenResult {
        let period = 1.0 / self.frequency_hz;
        let t_start = transient_cycles as f64 * period;
        let t_end = t_start + cycles as f64 * period;
        let mut state = State::Free {
            t0: 0.0,
            z0: start_m,
            u: 0.0,
        };
        let mut dissipated = 0.0; // per kg
        let mut impacts = 0u64;
        let mut t = 0.0;
        while t < t_end {
            match state {
                State::Free { t0, z0, u } => {
                    let (ti, side) = self.next_impact(t0, z0, u);
                    if ti >= t_end {
                        break;
                    }
                    let w = u - self.vc(ti);
                    let u_after = self.vc(ti) - self.restitution * w;
                    if ti >= t_start {
                        dissipated += 0.5 * (1.0 - self.restitution.powi(2)) * w * w;
                        impacts += 1;
                    }
                    t = ti;
                    let pushing = side * self.ac(ti) < 0.0;
                    state = if self.restitution == 0.0 && pushing {
                        State::Stuck { side }
                    } else {
                        State::Free {
                            t0: ti,
                            z0: self.xc(ti) + side * 0.5 * self.clearance_m,
                            u: u_after,
                        }
                    };
                }
                State::Stuck { side } => {
                    // The wall pushes while side·a_c < 0, i.e. side·sin(Ωt) > 0: until the next
                    // zero of sin(Ωt), Ωt = nπ (x_c = 0, |v_c| = V).
                    let n = (self.omega() * t / PI).floor() + 1.0;
                    let td = n * PI / self.omega();
                    t = td;
                    state = State::Free {
                        t0: td,
                        z0: self.xc(td) + side * 0.5 * self.clearance_m,
                        u: self.vc(td),
                    };
                }
            }
        }
        let per_cycle = dissipated / cycles as f64;
        let v = self.amplitude_m * self.omega();
        EventDrivenResult {
            dissipated_per_cycle_j_kg: per_cycle,
            effective_loss_factor: per_cycle / (2.0 * PI * 0.5 * v * v),
            impacts_per_cycle: impacts as f64 / cycles as f64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Large stroke: the particle leaves a wall at Ωt = nπ with |v| = V and hits the opposite wall
    /// at a time that solves V(t − t_off) ± h = X sin(Ωt) [D Eq. 6.6 form]; check against that
    /// equation solved here directly, and against the bound η̄ ≤ 4/π [D Eq. 6.10].
    #[test]
    fn plastic_collect_and_collide_matches_closed_form() {
        for x_over_h in [0.5, 1.0, 2.0] {
            let h = 3e-3;
            let d = SingleParticleDamper {
                clearance_m: h,
                amplitude_m: x_over_h * h,
                frequency_hz: 50.0,
                restitution: 0.0,
            };
            let r = d.simulate(0.0, 20, 20);
            // Closed form of the period-1 motion: leave the lower wall at Ωt = 0 (x_c = 0,
            // velocity +V); fly z = −h/2 + V t; impact the upper wall where
            // V t − h/2 = X sin(Ωt) + h/2, i.e. τ − sin τ = h/X with τ = Ωt.
            let mut lo = 0.0;
            let mut hi = 2.0 * PI;
            for _ in 0..200 {
                let m = 0.5 * (lo + hi);
                if m - m.sin() < h / d.amplitude_m {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            let tau = 0.5 * (lo + hi);
            // Relative speed at impact: V − V cos τ; two impacts per cycle.
            let w = 1.0 - tau.cos();
            let eta = 2.0 * 0.5 * w * w / (2.0 * PI * 0.5);
            assert!(
                (r.effective_loss_factor / eta - 1.0).abs() < 1e-6,
                "X/h = {x_over_h}: event-driven {} vs closed form {eta}",
                r.effective_loss_factor
            );
            assert!(r.effective_loss_factor <= 4.0 / PI + 1e-12);
            assert!((r.impacts_per_cycle - 2.0).abs() < 1e-12);
        }
    }

    /// Elastic impacts dissipate nothing.
    #[test]
    fn elastic_impacts_dissipate_nothing() {
        let d = SingleParticleDamper {
            clearance_m: 2e-3,
            amplitude_m: 1e-3,
            frequency_hz: 30.0,
            restitution: 1.0,
        };
        let r = d.simulate(0.0, 2, 5);
        assert_eq!(r.dissipated_per_cycle_j_kg, 0.0);
        assert!(r.impacts_per_cycle > 0.0);
    }
}
