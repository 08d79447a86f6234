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
    /// No values yet.
    pub const EMPTY: Interval = Interval {
        length_m: Band::EMPTY,
        current_a: Band::EMPTY,
        power_w: Band::EMPTY,
    };

    /// Widen by a sample's values (an output sample, or the state of an accepted
    /// step as a sample).
    pub fn add(&mut self, s: &Sample) {
        self.length_m.add(s.length_m);
        self.current_a.add(s.current_a);
        self.power_w.add(s.power_w);
    }

    fn union(&mut self, o: &Interval) {
        for (b, o) in [
            (&mut self.length_m, &o.length_m),
            (&mut self.current_a, &o.current_a),
            (&mut self.power_w, &o.power_w),
        ] {
            b.lo = b.lo.min(o.lo);
            b.hi = b.hi.max(o.hi);
        }
    }
}

/// The sampling check of a run and, when the samples do not resolve the motion, the
/// per-interval extremes of the trajectory at the integrator's accepted steps, built
/// as the run goes (nothing is held per sample but the bands of the kept ones).
///
/// A run that keeps only every k-th sample for its charts ([`Envelope::grouped`])
/// gets one band per kept sample: the extremes over the k output intervals it stands
/// for, so a decimated chart still shows every excursion of the full trajectory.
#[derive(Debug, Clone)]
pub struct Envelope {
    /// Damped mode frequency f_d (Hz); 0 without ringing (no inertia, ζ ≥ 1).
    damped_hz: f64,
    /// Largest output interval Δt (s).
    interval_s: f64,
    /// e^(−ζ·ω_n·Δt): what is left of the ringing one interval after it starts.
    decay: f64,
    /// Time of the last output sample (s).
    span_s: f64,
    /// Bands are built (the samples do not resolve the motion, or are decimated).
    banded: bool,
    /// Union of the bands since the last kept sample.
    group: Interval,
    /// The previous sample, if any.
    prev: Option<Sample>,
    /// Largest motion within an output interval that its end samples do not show (m).
    hidden: f64,
    /// Bands of the kept samples.
    bands: Vec<Interval>,
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
            span_s: times.last().copied().unwrap_or(0.0),
            banded: false,
            group: Interval::EMPTY,
            prev: None,
            hidden: 0.0,
            bands: Vec::new(),
        };
        e.banded = !e.resolved();
        e
    }

    /// Bands even where the samples resolve the motion: the run keeps only some of
    /// its samples for the charts, and each kept one stands for those it skipped.
    pub fn grouped(mut self) -> Envelope {
        self.banded = true;
        self
    }

    /// Whether the samples resolve the motion: no ringing, Nyquist satisfied, or
    /// ringing that dies within one output interval.
    pub fn resolved(&self) -> bool {
        !(self.damped_hz.is_finite() && self.damped_hz > 0.0)
            || 2.0 * self.damped_hz * self.interval_s < 1.0
            || self.decay <= DIED_OUT
    }

    /// Whether the integrator's accepted steps between samples are wanted
    /// ([`Envelope::sample`]): only where the samples do not resolve the motion.
    pub fn wants_steps(&self) -> bool {
        !self.resolved()
    }

    /// The next output sample, with the extremes of the accepted steps since the
    /// previous one (`steps`; empty when not wanted), and whether the run keeps it.
    /// Its band is the interval's steps and both end samples (sample 0: itself).
    pub fn sample(&mut self, s: &Sample, steps: Interval, kept: bool) {
        if !self.banded {
            return;
        }
        let mut band = steps;
        band.add(s);
        if let Some(prev) = &self.prev {
            band.add(prev);
            self.hidden = self.hidden.max(hidden_in(&band, prev, s));
        }
        self.group.union(&band);
        if kept {
            self.bands
                .push(std::mem::replace(&mut self.group, Interval::EMPTY));
        }
        self.prev = Some(*s);
    }

    /// The bands aligned with the kept samples (sample k: the extremes over its
    /// output intervals, the samples at both ends included; sample 0: itself), or
    /// `None` when the samples resolve the motion and are all kept; and the warning to
    /// give when they do not resolve it. `last`: the run's last sample was not kept,
    /// and the caller keeps it now.
    pub fn finish(mut self, last: bool) -> (Option<Vec<Interval>>, Option<String>) {
        if !self.banded {
            return (None, None);
        }
        if last {
            self.bands.push(self.group);
        }
        if self.resolved() {
            return (Some(self.bands), None);
        }
        let fs = 1.0 / self.interval_s;
        // The alias: f_d folded into [0, fs/2].
        let folded = self.damped_hz % fs;
        let alias = folded.min(fs - folded);
        let warning = format!(
            "the output samples ({}) do not resolve the axial mode ({} damped, {:.0} % of its ringing left after one output interval): sampled, it appears as a {} oscillation that does not exist; within output intervals the stroke moves by up to {} more than the samples show, so the charts draw the min/max per output interval from the integrator's steps; give more than {:.0} samples over the {} span (Nyquist) to resolve it",
            si(fs, "Hz"),
            si(self.damped_hz, "Hz"),
            100.0 * self.decay,
            si(alias, "Hz"),
            si(self.hidden, "m"),
            (2.0 * self.damped_hz * self.span_s).ceil(),
            si(self.span_s, "s")
        );
        (Some(self.bands), Some(warning))
    }
}

/// The length change within an output interval (band `b`, end samples `a`, `s`)
/// that the end samples do not show: band width minus the change between them (m);
/// 0 when not finite.
fn hidden_in(b: &Interval, a: &Sample, s: &Sample) -> f64 {
    let w = (b.length_m.hi - b.length_m.lo) - (s.length_m - a.length_m).abs();
    if w.is_finite() {
        w
    } else {
        0.0
    }
}

/// The largest length change within an output interval that its end samples do not
/// show: band width minus the change between the samples (m). Ringing of amplitude A
/// gives ≈ 2A; a monotone move between samples gives ≈ 0.
pub fn hidden_motion(bands: &[Interval], samples: &[Sample]) -> f64 {
    (1..bands.len().min(samples.len()))
        .map(|k| hidden_in(&bands[k], &samples[k - 1], &samples[k]))
        .fold(0.0, f64::max)
}
