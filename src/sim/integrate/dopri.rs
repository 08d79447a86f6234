//! Our own explicit Dormand–Prince 5(4) (Dormand & Prince 1980) with Hairer's
//! 4th-order continuous extension (dense output) and a PI step controller
//! (Gustafsson 1991). It is the independent test oracle for the implicit methods and
//! the only method with a fixed-step mode (for convergence-order tests).
//!
//! Between restart times it writes the state at requested sample times from the
//! dense output, locates the first change of the event function from positive to
//! non-positive by bisection on the dense output, and allocates nothing per step:
//! all buffers live in a [`Workspace`] created once per run.

use super::{
    budget_exhausted, initial_step, left_limit, non_finite, End, EventFn, Left, Options, Stats,
    StepFn, System,
};

/// Buffers reused by every step.
struct Workspace {
    n: usize,
    k: [Vec<f64>; 7],
    y1: Vec<f64>,
    ytmp: Vec<f64>,
    err: Vec<f64>,
    dense: [Vec<f64>; 5],
    h: f64,
    err_old: f64,
}

impl Workspace {
    fn new(n: usize) -> Self {
        let v = || vec![0.0; n];
        Workspace {
            n,
            k: [v(), v(), v(), v(), v(), v(), v()],
            y1: v(),
            ytmp: v(),
            err: v(),
            dense: [v(), v(), v(), v(), v()],
            h: 0.0,
            err_old: 1e-4,
        }
    }
}

const A: [[f64; 6]; 6] = [
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [
        19372.0 / 6561.0,
        -25360.0 / 2187.0,
        64448.0 / 6561.0,
        -212.0 / 729.0,
        0.0,
        0.0,
    ],
    [
        9017.0 / 3168.0,
        -355.0 / 33.0,
        46732.0 / 5247.0,
        49.0 / 176.0,
        -5103.0 / 18656.0,
        0.0,
    ],
    [
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
    ],
];
const C: [f64; 6] = [0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0];
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];
const D: [f64; 7] = [
    -12715105075.0 / 11282082432.0,
    0.0,
    87487479700.0 / 32700410799.0,
    -10690763975.0 / 1880347072.0,
    701980252875.0 / 199316789632.0,
    -1453857185.0 / 822651844.0,
    69997945.0 / 29380423.0,
];

/// Weighted RMS norm of the local error (all states, atol scaled per state).
pub(super) fn wrms(e: &[f64], y0: &[f64], y1: &[f64], scale: &[f64], o: &Options) -> f64 {
    let mut s = 0.0;
    for i in 0..e.len() {
        let sc = o.atol * scale[i] + o.rtol * y0[i].abs().max(y1[i].abs());
        s += (e[i] / sc).powi(2);
    }
    (s / e.len() as f64).sqrt()
}

/// Dense output of the last accepted step into `out` at θ ∈ [0, 1].
fn dense_eval(w: &Workspace, theta: f64, out: &mut [f64]) {
    let d = &w.dense;
    let t1 = 1.0 - theta;
    for i in 0..w.n {
        out[i] = d[0][i] + theta * (d[1][i] + t1 * (d[2][i] + theta * (d[3][i] + t1 * d[4][i])));
    }
}

/// Integrate over the restart intervals `bounds` (see [`super::run`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn run<S: System>(
    sys: &S,
    o: &Options,
    scale: &[f64],
    bounds: &[f64],
    y: &mut [f64],
    samples: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
    step: &mut StepFn,
    event: Option<EventFn>,
    restart: &mut dyn FnMut(f64, &mut [f64]),
    stats: &mut Stats,
) -> End {
    let mut w = Workspace::new(y.len());
    let mut si = 0;
    for (k, win) in bounds.windows(2).enumerate() {
        let (a, b) = (win[0], win[1]);
        if k > 0 {
            stats.restarts += 1;
            restart(a, y);
        }
        let s_end = samples[si..].partition_point(|&t| t <= b) + si;
        let end = segment(
            sys,
            o,
            scale,
            &mut w,
            stats,
            a,
            b,
            y,
            &samples[si..s_end],
            out,
            step,
            event,
        );
        si = s_end;
        if end != End::Done {
            return end;
        }
    }
    End::Done
}

/// Integrate `y` from `t0` to `t1` (one segment between restarts).
#[allow(clippy::too_many_arguments)]
fn segment<S: System>(
    sys: &S,
    o: &Options,
    scale: &[f64],
    w: &mut Workspace,
    stats: &mut Stats,
    t0: f64,
    t1: f64,
    y: &mut [f64],
    samples: &[f64],
    out: &mut dyn FnMut(f64, &[f64]),
    step: &mut StepFn,
    event: Option<EventFn>,
) -> End {
    let sys = Left {
        sys,
        t_end: left_limit(t0, t1),
    };
    let mut t = t0;
    let mut next_sample = 0;
    sys.rhs(t, y, &mut w.k[0]);
    stats.rhs_evals += 1;
    if w.h <= 0.0 || w.h > t1 - t0 {
        w.h = initial_step(y, &w.k[0], scale, o)
            .min(t1 - t0)
            .min(o.h_max)
            .min(o.h_init);
    }
    if let Some(h) = o.fixed_step {
        w.h = h;
    }
    let mut g_old = event.map(|g| g(t, y));
    if g_old.is_some_and(|g| g <= 0.0) {
        // already past the event (e.g. an input jump at the restart)
        return End::Event(t);
    }
    while t < t1 {
        if stats.steps + stats.rejected >= o.max_steps {
            return budget_exhausted(t, o.max_steps);
        }
        let mut h = w.h.min(o.h_max);
        let last = t + h >= left_limit(t0, t1);
        if last {
            h = t1 - t;
        }
        if h < 1e-14 * t1.abs().max(1.0) {
            // Rejections down to underflow: say why, when it was a non-finite trial.
            return non_finite(t + h, &w.y1)
                .unwrap_or_else(|| End::Failed(format!("step size underflow at t = {t:.6e} s")));
        }
        let err = dp54_step(&sys, w, t, h, y, scale, o, stats);
        if o.fixed_step.is_none() {
            if err > 1.0 {
                stats.rejected += 1;
                w.h = h * (0.9 * err.powf(-0.2)).clamp(0.2, 1.0);
                continue;
            }
            // PI controller (Gustafsson) on accepted steps
            let e = err.max(1e-10);
            let fac = 0.9 * e.powf(-0.7 / 5.0) * w.err_old.powf(0.4 / 5.0);
            w.err_old = e;
            if !last {
                w.h = h * fac.clamp(0.2, 5.0);
            }
        }
        // An infinite state passes the error test (its tolerance is infinite too).
        if let Some(end) = non_finite(t + h, &w.y1) {
            return end;
        }
        stats.steps += 1;
        let t_new = if last { t1 } else { t + h };
        // event: sign change of g over the step, located on the dense output
        if let (Some(g), Some(g0)) = (event, g_old) {
            let g1 = g(t_new, &w.y1);
            if g0 > 0.0 && g1 <= 0.0 {
                let (mut a, mut b) = (0.0, 1.0);
                for _ in 0..60 {
                    let mid = 0.5 * (a + b);
                    let mut tmp = std::mem::take(&mut w.ytmp);
                    dense_eval(w, mid, &mut tmp);
                    let gm = g(t + mid * h, &tmp);
                    w.ytmp = tmp;
                    if gm > 0.0 {
                        a = mid;
                    } else {
                        b = mid;
                    }
                }
                let te = t + b * h;
                while next_sample < samples.len() && samples[next_sample] < te {
                    let ts = samples[next_sample];
                    dense_eval(w, (ts - t) / h, y);
                    out(ts, y);
                    next_sample += 1;
                }
                dense_eval(w, b, y);
                return End::Event(te);
            }
            g_old = Some(g1);
        }
        while next_sample < samples.len() && samples[next_sample] <= t_new {
            let ts = samples[next_sample];
            let mut tmp = std::mem::take(&mut w.ytmp);
            dense_eval(w, ((ts - t) / h).clamp(0.0, 1.0), &mut tmp);
            out(ts, &tmp);
            w.ytmp = tmp;
            next_sample += 1;
        }
        y.copy_from_slice(&w.y1);
        t = t_new;
        step(t, y);
        // FSAL: k[0] ← f(t_new, y)
        let (a, b) = w.k.split_at_mut(6);
        a[0].copy_from_slice(&b[0]);
    }
    End::Done
}

/// One Dormand–Prince step; returns the error norm (∞ if the step is not finite).
#[allow(clippy::too_many_arguments)]
fn dp54_step<S: System>(
    sys: &Left<S>,
    w: &mut Workspace,
    t: f64,
    h: f64,
    y: &[f64],
    scale: &[f64],
    o: &Options,
    stats: &mut Stats,
) -> f64 {
    let n = w.n;
    for s in 0..6 {
        for i in 0..n {
            let mut acc = 0.0;
            for j in 0..=s {
                acc += A[s][j] * w.k[j][i];
            }
            w.ytmp[i] = y[i] + h * acc;
        }
        sys.rhs(t + C[s] * h, &w.ytmp, &mut w.k[s + 1]);
    }
    stats.rhs_evals += 6;
    // ytmp now holds the 5th-order solution (row 6 of A = b); k[6] = f(t+h, y1)
    w.y1.copy_from_slice(&w.ytmp);
    for i in 0..n {
        let mut e = 0.0;
        for j in 0..7 {
            e += E[j] * w.k[j][i];
        }
        w.err[i] = h * e;
    }
    let err = wrms(&w.err, y, &w.y1, scale, o);
    for i in 0..n {
        let dy = w.y1[i] - y[i];
        let bsp = h * w.k[0][i] - dy;
        w.dense[0][i] = y[i];
        w.dense[1][i] = dy;
        w.dense[2][i] = bsp;
        w.dense[3][i] = dy - h * w.k[6][i] - bsp;
        let mut acc = 0.0;
        for j in 0..7 {
            acc += D[j] * w.k[j][i];
        }
        w.dense[4][i] = h * acc;
    }
    if err.is_finite() {
        err
    } else {
        f64::INFINITY
    }
}
