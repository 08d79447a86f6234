//! Whether the output samples resolve the motion, and the envelope that charts draw
//! where they do not.
//!
//! A lightly damped axial mode rings at f_d = f_n·√(1 − ζ²) after every fast input.
//! Samples Δt apart (Δt the largest output interval) show that ringing only if
//! 1/Δt > 2·f_d (Nyquist); otherwise the sampled line is an alias at |f_d − k/Δt|, a
//! slow oscillation that does not exist. Ringing whose amplitude falls by 100× within
//! one output interval (e^(−ζ·ω_n·Δt) ≤ 0.01) has died before the sample after its
//! excitation: the samples then miss nothing worth drawing, whatever f_d. Where the
//! samples cannot resolve the mode, the extremes of the trajectory over each output
//! interval, taken from the integrator's accepted steps, are what a chart can draw
//! truthfully.

use super::fidelity::AxialMode;
use super::Sample;
use crate::report::format::si;
use std::f64::consts::PI;

/// Ringing amplitude ratio over one output interval below which it does not matter.
const DIED_OUT: f64 = 0.01;

/// Smallest and largest value over an output interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Band {
    /// Smallest value.
    pub lo: f64,
    /// Largest value.
    pub hi: f64,
}

impl Band {
    const EMPTY: Band = Band {
        lo: f64::INFINITY,
        hi: f64::NEG_INFINITY,
    };

    fn add(&mut self, v: f64) {
        if v.is_finite() {
            self.lo = self.lo.min(v);
            self.hi = self.hi.max(v);
        }
    }
}

/// Extremes of the charted quantities over one output interval (t_{k−1}, t_k].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Actuator length (m).
    pub length_m: Band,
    /// Current (A).
    pub current_a: Band,
    /// Electrical power (W).
    pub power_w: Band,
}

impl Interval {
    const EMPTY: Interval = Interval {
        length_m: Band::EMPTY,
        current_a: Band::EMPTY,
        power_w: Band::EMPTY,
    };

    fn add(&mut self, s: &Sample) {
        self.length_m.add(s.length_m);
        self.current_a.add(s.current_a);
        self.power_w.add(s.power_w);
    }
}

/// The sampling check of a run and, when the samples do not resolve the motion, the
/// per-interval extremes of the trajectory at the integrator's accepted steps.
#[derive(Debug, Clone)]
pub struct Envelope {
    /// Damped mode frequency f_d (Hz); 0 without ringing (no inertia, ζ ≥ 1).
    damped_hz: f64,
    /// Largest output interval Δt (s).
    interval_s: f64,
    /// e^(−ζ·ω_n·Δt): what is left of the ringing one interval after it starts.
    decay: f64,
    /// Output sample times after t = 0 (s).
    times: Vec<f64>,
    /// Interval being filled: index into `times`.
    k: usize,
    /// Extremes of the accepted steps in each interval; empty when resolved.
    acc: Vec<Interval>,
}

impl Envelope {
    /// Check the sampling of a run: `inertia` of the plant that runs, the axial mode
    /// and the output sample times after t = 0.
    pub fn new(inertia: bool, mode: &AxialMode, times: &[f64]) -> Envelope {
        let z = mode.damping_ratio;
        let damped_hz = if inertia && z < 1.0 {
            mode.frequency_hz * (1.0 - z * z).sqrt()
        } else {
            0.0
        };
        let interval_s = times
            .iter()
            .scan(0.0, |prev, &t| {
                let d = t - *prev;
                *prev = t;
                Some(d)
            })
            .fold(0.0, f64::max);
        let decay = (-z * 2.0 * PI * mode.frequency_hz * interval_s).exp();
        let mut e = Envelope {
            damped_hz,
            interval_s,
            decay,
            times: times.to_vec(),
            k: 0,
            acc: Vec::new(),
        };
        if !e.resolved() {
            e.acc = vec![Interval::EMPTY; times.len()];
        }
        e
    }

    /// Whether the samples resolve the motion: no ringing, Nyquist satisfied, or
    /// ringing that dies within one output interval.
    pub fn resolved(&self) -> bool {
        !(self.damped_hz.is_finite() && self.damped_hz > 0.0)
            || 2.0 * self.damped_hz * self.interval_s < 1.0
            || self.decay <= DIED_OUT
    }

    /// The state at the end of an accepted step (as a sample): widens its interval.
    pub fn add(&mut self, s: &Sample) {
        if self.acc.is_empty() {
            return;
        }
        while self.k < self.times.len() && s.time_s > self.times[self.k] {
            self.k += 1;
        }
        if let Some(i) = self.acc.get_mut(self.k) {
            i.add(s);
        }
    }

    /// The run's envelope aligned with its `samples` (sample k: the extremes over
    /// (t_{k−1}, t_k], the samples at both ends included; sample 0: itself), or `None`
    /// when the samples resolve the motion; and the warning to give then.
    pub fn finish(self, samples: &[Sample]) -> (Option<Vec<Interval>>, Option<String>) {
        if self.acc.is_empty() {
            return (None, None);
        }
        let bands: Vec<Interval> = (0..samples.len())
            .map(|k| {
                let mut i = match k {
                    0 => Interval::EMPTY,
                    _ => self.acc.get(k - 1).copied().unwrap_or(Interval::EMPTY),
                };
                i.add(&samples[k]);
                if k > 0 {
                    i.add(&samples[k - 1]);
                }
                i
            })
            .collect();
        let hidden = hidden_motion(&bands, samples);
        let fs = 1.0 / self.interval_s;
        // The alias: f_d folded into [0, fs/2].
        let folded = self.damped_hz % fs;
        let alias = folded.min(fs - folded);
        let span = self.times.last().copied().unwrap_or(0.0);
        let warning = format!(
            "the output samples ({}) do not resolve the axial mode ({} damped, {:.0} % of its ringing left after one output interval): sampled, it appears as a {} oscillation that does not exist; within output intervals the stroke moves by up to {} more than the samples show, so the charts draw the min/max per output interval from the integrator's steps; give more than {:.0} samples over the {} span (Nyquist) to resolve it",
            si(fs, "Hz"),
            si(self.damped_hz, "Hz"),
            100.0 * self.decay,
            si(alias, "Hz"),
            si(hidden, "m"),
            (2.0 * self.damped_hz * span).ceil(),
            si(span, "s")
        );
        (Some(bands), Some(warning))
    }
}

/// The largest length change within an output interval that its end samples do not
/// show: band width minus the change between the samples (m). Ringing of amplitude A
/// gives ≈ 2A; a monotone move between samples gives ≈ 0.
pub fn hidden_motion(bands: &[Interval], samples: &[Sample]) -> f64 {
    (1..bands.len().min(samples.len()))
        .map(|k| {
            let b = bands[k].length_m;
            (b.hi - b.lo) - (samples[k].length_m - samples[k - 1].length_m).abs()
        })
        .filter(|w| w.is_finite())
        .fold(0.0, f64::max)
}
