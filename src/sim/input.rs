//! Input waveforms: step, ramp, triangle, sine, piecewise-linear (from CSV), a
//! measured signal (smooth between its real corners, [`measured`]) and sums.
//!
//! A waveform is plain data; [`Waveform::eval`] returns the value and its time
//! derivative, [`Waveform::kinks`] the times where either is discontinuous (the
//! integrator restarts there).

pub mod measured;

use super::budget::MAX_KINKS;
pub use measured::Measured;
use std::f64::consts::PI;
use std::sync::Arc;

/// One term of an input signal (SI units: V for voltages, 1 for a PID reference).
#[derive(Debug, Clone, PartialEq)]
pub enum Term {
    /// `amplitude` from time `at` on (0 before).
    Step {
        /// Switching time (s).
        at: f64,
        /// Level after the step.
        amplitude: f64,
    },
    /// Linear from `from` at `start` to `to` at `end`; constant outside.
    Ramp {
        /// Start time (s).
        start: f64,
        /// End time (s).
        end: f64,
        /// Level before and at `start`.
        from: f64,
        /// Level at and after `end`.
        to: f64,
    },
    /// Symmetric triangle between `offset` and `offset + amplitude`, starting at its
    /// low point at `start`, for `cycles` periods (then back at `offset`).
    Triangle {
        /// Start time (s).
        start: f64,
        /// Peak-to-valley height.
        amplitude: f64,
        /// Frequency (Hz).
        frequency: f64,
        /// Number of periods (peaks).
        cycles: f64,
        /// Base level.
        offset: f64,
    },
    /// `offset + amplitude·sin(2πf(t − start) + phase)` for t ≥ start, for `cycles`
    /// periods (infinite if None); holds its first value before and its last after.
    Sine {
        /// Start time (s).
        start: f64,
        /// Amplitude.
        amplitude: f64,
        /// Frequency (Hz).
        frequency: f64,
        /// Phase (rad).
        phase: f64,
        /// Mean level.
        offset: f64,
        /// Number of periods, or unlimited.
        cycles: Option<f64>,
    },
    /// Piecewise linear through (t, value) points (sorted, constant outside).
    Pwl {
        /// Points (s, value).
        points: Vec<(f64, f64)>,
    },
    /// A measured signal: one smooth piece between each two of its corners (shared:
    /// a scene clone does not copy the samples).
    Measured(Arc<Measured>),
}

/// A sum of terms.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Waveform {
    /// The terms, summed.
    pub terms: Vec<Term>,
}

/// ⌊s⌋ for 0 ≤ s (finite), through an integer conversion where s < 2⁵² (every
/// larger double is an integer): the same value as `f64::floor`, without its
/// library call on targets without SSE4.1 (the triangle's phase at every
/// right-hand side).
#[inline]
fn floor_non_negative(s: f64) -> f64 {
    const INTEGRAL: f64 = 4_503_599_627_370_496.0; // 2⁵²
    if s < INTEGRAL {
        (s as i64) as f64
    } else {
        s
    }
}

impl Term {
    /// Value and time derivative at `t` (right-continuous at kinks).
    pub fn eval(&self, t: f64) -> (f64, f64) {
        match *self {
            Term::Step { at, amplitude } => (if t >= at { amplitude } else { 0.0 }, 0.0),
            Term::Ramp {
                start,
                end,
                from,
                to,
            } => {
                if t < start {
                    (from, 0.0)
                } else if t >= end {
                    (to, 0.0)
                } else {
                    let r = (to - from) / (end - start);
                    (from + r * (t - start), r)
                }
            }
            Term::Triangle {
                start,
                amplitude,
                frequency,
                cycles,
                offset,
            } => {
                let s = (t - start) * frequency;
                if s < 0.0 || s >= cycles {
                    return (offset, 0.0);
                }
                let ph = s - floor_non_negative(s);
                let r = 2.0 * amplitude * frequency;
                if ph < 0.5 {
                    (offset + 2.0 * amplitude * ph, r)
                } else {
                    (offset + 2.0 * amplitude * (1.0 - ph), -r)
                }
            }
            Term::Sine {
                start,
                amplitude,
                frequency,
                phase,
                offset,
                cycles,
            } => {
                let s = (t - start) * frequency;
                let w = 2.0 * PI * frequency;
                if s < 0.0 {
                    return (offset + amplitude * phase.sin(), 0.0);
                }
                if let Some(c) = cycles.filter(|&c| s >= c) {
                    return (offset + amplitude * (2.0 * PI * c + phase).sin(), 0.0);
                }
                let a = w * (t - start) + phase;
                (offset + amplitude * a.sin(), amplitude * w * a.cos())
            }
            Term::Pwl { ref points } => {
                let i = points.partition_point(|p| p.0 <= t);
                if i == 0 {
                    (points[0].1, 0.0)
                } else if i == points.len() {
                    (points[i - 1].1, 0.0)
                } else {
                    let (a, b) = (points[i - 1], points[i]);
                    let r = (b.1 - a.1) / (b.0 - a.0);
                    (a.1 + r * (t - a.0), r)
                }
            }
            Term::Measured(ref m) => m.eval(t),
        }
    }

    /// Times in [t0, t1] where the value or its derivative jumps, at most
    /// [`MAX_KINKS`] + 2 of them: the allocation never follows a user's count (a
    /// triangle of 1e30 cycles); [`Term::kink_count`] says how many there are, and
    /// `sim::budget` refuses a run with more than `MAX_KINKS` before it starts.
    pub fn kinks(&self, t0: f64, t1: f64) -> Vec<f64> {
        let inside = |x: &f64| *x >= t0 && *x <= t1;
        match *self {
            Term::Step { at, .. } => [at].into_iter().filter(inside).collect(),
            Term::Ramp { start, end, .. } => [start, end].into_iter().filter(inside).collect(),
            Term::Triangle {
                start,
                frequency,
                cycles,
                ..
            } => {
                // corners start + i/(2f), i = 0 … ⌈2·cycles⌉, then the end at cycles/f
                let (lo, hi) = self.corner_range(t0, t1);
                let mut k: Vec<f64> = (0..=MAX_KINKS as u64)
                    .map(|j| lo + j as f64)
                    .take_while(|&i| i <= hi)
                    .map(|i| start + 0.5 * i / frequency)
                    .filter(inside)
                    .collect();
                k.extend([start + cycles / frequency].into_iter().filter(inside));
                k
            }
            Term::Sine {
                start,
                frequency,
                cycles,
                ..
            } => match cycles {
                Some(c) => [start, start + c / frequency]
                    .into_iter()
                    .filter(inside)
                    .collect(),
                None => [start].into_iter().filter(inside).collect(),
            },
            Term::Pwl { ref points } => points
                .iter()
                .map(|p| p.0)
                .filter(inside)
                .take(MAX_KINKS + 1)
                .collect(),
            Term::Measured(ref m) => m
                .corners()
                .iter()
                .copied()
                .filter(inside)
                .take(MAX_KINKS + 1)
                .collect(),
        }
    }

    /// Corner indices [lo, hi] of a triangle within [t0, t1] (empty if lo > hi).
    fn corner_range(&self, t0: f64, t1: f64) -> (f64, f64) {
        match *self {
            Term::Triangle {
                start,
                frequency,
                cycles,
                ..
            } => (
                ((t0 - start) * 2.0 * frequency).ceil().max(0.0),
                ((t1 - start) * 2.0 * frequency)
                    .floor()
                    .min((2.0 * cycles).ceil()),
            ),
            _ => (1.0, 0.0),
        }
    }

    /// How many kinks lie in [t0, t1], counted without listing them (as f64: a
    /// user's count may exceed any integer type).
    pub fn kink_count(&self, t0: f64, t1: f64) -> f64 {
        match self {
            Term::Triangle { .. } => {
                let (lo, hi) = self.corner_range(t0, t1);
                (hi - lo + 1.0).max(0.0) + 1.0
            }
            Term::Pwl { points } => points.iter().filter(|p| p.0 >= t0 && p.0 <= t1).count() as f64,
            Term::Measured(m) => m.corners().iter().filter(|&&c| c >= t0 && c <= t1).count() as f64,
            _ => self.kinks(t0, t1).len() as f64,
        }
    }

    /// The shortest time scale of the term (s): ramp duration, quarter period,
    /// shortest PWL segment, shortest measured piece; zero for a step (a jump).
    pub fn time_scale(&self) -> f64 {
        match *self {
            Term::Step { .. } => 0.0,
            Term::Ramp { start, end, .. } => end - start,
            Term::Triangle { frequency, .. } => 0.5 / frequency,
            Term::Sine { frequency, .. } => 1.0 / (2.0 * PI * frequency),
            Term::Pwl { ref points } => points
                .windows(2)
                .map(|w| w[1].0 - w[0].0)
                .fold(f64::INFINITY, f64::min),
            Term::Measured(ref m) => m.shortest_piece(),
        }
    }
}

impl Waveform {
    /// Value and derivative of the sum at `t`.
    #[inline]
    pub fn eval(&self, t: f64) -> (f64, f64) {
        self.terms.iter().fold((0.0, 0.0), |(v, d), term| {
            let (a, b) = term.eval(t);
            (v + a, d + b)
        })
    }

    /// Sorted, deduplicated kink times strictly inside (t0, t1).
    pub fn kinks(&self, t0: f64, t1: f64) -> Vec<f64> {
        let tol = 1e-12 * (t1 - t0).abs().max(1e-300);
        let mut k: Vec<f64> = self
            .terms
            .iter()
            .flat_map(|t| t.kinks(t0, t1))
            .filter(|&x| x > t0 + tol && x < t1 - tol)
            .collect();
        k.sort_by(f64::total_cmp);
        k.dedup_by(|a, b| (*a - *b).abs() <= tol);
        k
    }

    /// How many kinks the terms have in [t0, t1] (see [`Term::kink_count`]).
    pub fn kink_count(&self, t0: f64, t1: f64) -> f64 {
        self.terms.iter().map(|t| t.kink_count(t0, t1)).sum()
    }

    /// Shortest time scale over the terms (0 if any term jumps).
    pub fn time_scale(&self) -> f64 {
        self.terms
            .iter()
            .map(Term::time_scale)
            .fold(f64::INFINITY, f64::min)
    }

    /// Largest absolute value over [t0, t1]. A sum of steps, ramps, triangles and
    /// piecewise-linear terms is linear between its kinks (when they are all listed:
    /// at most [`MAX_KINKS`]), so the largest |value| is at an end of a piece: the
    /// right value at its start or the left limit at its end (2·v(midpoint) −
    /// v(start), exact on a linear piece). Other waveforms are sampled at the kinks
    /// and densely in between (20 001 evaluations: a tenth of a 100 Hz triangle's
    /// run when it was sampled too), and the largest sample is refined by
    /// golden-section search between its neighbours (a sine sampled 20 times a
    /// period shows its peak 1.2 % low; refined, to 10⁻¹² of the step).
    pub fn max_abs(&self, t0: f64, t1: f64) -> f64 {
        let v = |t: f64| self.eval(t).0;
        let linear = |t: &Term| {
            matches!(
                t,
                Term::Step { .. } | Term::Ramp { .. } | Term::Triangle { .. } | Term::Pwl { .. }
            )
        };
        if self.terms.iter().all(linear) && self.kink_count(t0, t1) <= MAX_KINKS as f64 {
            let mut ts: Vec<f64> = [t0, t1].into_iter().chain(self.kinks(t0, t1)).collect();
            ts.sort_by(f64::total_cmp);
            ts.dedup();
            return ts
                .windows(2)
                .map(|w| {
                    let a = v(w[0]);
                    a.abs().max((2.0 * v(0.5 * (w[0] + w[1])) - a).abs())
                })
                .fold(v(t1).abs(), f64::max);
        }
        let n = 20_000;
        let dt = (t1 - t0) / n as f64;
        let grid = |i: usize| t0 + dt * i as f64;
        let (best, top) = (0..=n)
            .map(|i| (i, v(grid(i)).abs()))
            .fold((0, 0.0), |b, x| if x.1 > b.1 { x } else { b });
        let (a, b) = (grid(best.saturating_sub(1)), grid((best + 1).min(n)));
        let refined = crate::sim::static_curve::golden_max(&|t| v(t).abs(), a, b, 1e-12 * dt);
        self.kinks(t0, t1)
            .into_iter()
            .chain([refined])
            .map(|t| v(t).abs())
            .fold(top, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sine sampled 20 times a period with its peaks halfway between samples
    /// (phase π/20 at 100 Hz over 10 s, the 20 001-point grid every 0.5 ms) shows
    /// them 1.2 % low (cos(π/20)); the refined largest value is the amplitude to
    /// 10⁻⁹ (golden section to 10⁻¹² of the step leaves (10⁻¹²)² of it).
    #[test]
    fn a_sine_peak_between_samples_is_found() {
        let w = Waveform {
            terms: vec![Term::Sine {
                start: 0.0,
                amplitude: 1000.0,
                frequency: 100.0,
                phase: 0.05 * std::f64::consts::PI,
                offset: 0.0,
                cycles: None,
            }],
        };
        let sampled = (0..=20_000)
            .map(|i| w.eval(10.0 * i as f64 / 20_000.0).0.abs())
            .fold(0.0, f64::max);
        assert!(sampled < 0.99 * 1000.0, "{sampled}");
        let got = w.max_abs(0.0, 10.0);
        assert!((got - 1000.0).abs() <= 1e-9 * 1000.0, "{got}");
    }

    /// The integer-conversion floor is `f64::floor` bit for bit on [0, ∞): at and
    /// around integers, at 2⁵² and beyond, and on a sweep of fractions.
    #[test]
    fn floor_non_negative_is_floor() {
        let big = 4_503_599_627_370_496.0_f64;
        let mut xs = vec![0.0, 0.5, 1.0, 2.0 - f64::EPSILON, 3.0, 1e15 + 0.5, 1e300];
        xs.extend([big - 0.5, big, big + 1.0, 2.0 * big + 2.0]);
        xs.extend((0..10_000).map(|i| i as f64 * 0.0137));
        for x in xs {
            assert_eq!(floor_non_negative(x).to_bits(), x.floor().to_bits(), "{x}");
        }
    }
}
