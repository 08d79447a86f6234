//! Our own explicit Runge–Kutta 5(4) pairs of seven stages, the last at the new
//! state (FSAL), with a PI step controller ([`Scheme::gains`]: Gustafsson's
//! PI.3.4 for the pairs, Söderlind's PI.4.2 for Dormand–Prince 8(5,3)):
//! * [`DP54`]: Dormand–Prince 5(4) (Dormand & Prince 1980) with Hairer's 4th-order
//!   continuous extension. The independent test oracle for the implicit methods and
//!   the only method with a fixed-step mode (for convergence-order tests).
//! * [`TSIT45`]: Tsitouras 5(4) (Tsitouras 2011, Comput. Math. Appl. 62(2) 770–775)
//!   with its 4th-order interpolant: the plain runs of [`super::Method::Tsit45`].
//!   diffsol's Tsitouras (an I controller, gain 1/5, growth ≤ 2×) rejected 27 % of
//!   its steps on the ringing stack (73 k of 276 k; issue 12).
//!
//! The same driver steps Dormand–Prince 8(5,3) ([`super::dop853`], [`Scheme`]).
//!
//! Between restart times it writes the state at requested sample times from the
//! dense output, locates the first change of the event function from positive to
//! non-positive by bisection on the dense output, and allocates nothing per step:
//! all buffers live in a [`Workspace`] created once per run.

use super::{
    budget_exhausted, dop853, initial_step, left_limit, non_finite, End, EventFn, Left, Options,
    Stats, StepFn, System,
};

/// The explicit method a run steps with.
#[derive(Clone, Copy)]
pub(super) enum Scheme {
    /// A 5(4) pair of seven stages, FSAL ([`DP54`], [`TSIT45`]).
    Pair(&'static Pair),
    /// Dormand–Prince 8(5,3) ([`super::dop853`]).
    Dop853,
}

impl Scheme {
    /// Stage vectors a step holds.
    fn stages(self) -> usize {
        match self {
            Scheme::Pair(_) => 7,
            Scheme::Dop853 => dop853::STAGES,
        }
    }
    /// The stage holding f(t + h, y1), the next step's first (FSAL).
    fn last(self) -> usize {
        match self {
            Scheme::Pair(_) => 6,
            Scheme::Dop853 => dop853::LAST,
        }
    }
    /// Vectors of the dense output.
    fn dense(self) -> usize {
        match self {
            Scheme::Pair(_) => 5,
            Scheme::Dop853 => dop853::DENSE,
        }
    }
    /// q in the step-size control's exponents 1/q (the error estimate is
    /// O(h^q)): 5 for the 5(4) pairs, 8 for Dormand–Prince 8(5,3).
    fn exponent(self) -> f64 {
        match self {
            Scheme::Pair(_) => 5.0,
            Scheme::Dop853 => 8.0,
        }
    }
    /// The PI controller's gains (k_I + k_P, k_P): an accepted step's successor is
    /// h·0.9·err_n^(−(k_I + k_P)/q)·err_(n−1)^(k_P/q) (Söderlind, "Automatic
    /// control and adaptive time-stepping", Numer. Algorithms 31, 2002).
    /// * The 5(4) pairs: PI.3.4, k_I = 0.3, k_P = 0.4 (Gustafsson 1991; Hairer,
    ///   Nørsett & Wanner I, §II.4, dopri5's β1 = 0.7/5, β2 = 0.4/5).
    /// * Dormand–Prince 8(5,3): PI.4.2, k_I = 0.4, k_P = 0.2. On the seed stack
    ///   ringing at 1 kHz, where the error estimate swings 45-fold within each
    ///   half period (the velocity's weight follows its own zero crossings),
    ///   PI.3.4's smaller integral gain chases the swing and rejects 5 % of its
    ///   steps (3360 of 69 786 on the undamped 10 s step); PI.4.2 settles into the
    ///   swing's cycle and rejects 1, for 13 % fewer right-hand sides (730 081
    ///   against 843 433). Hairer's own choice for dop853.f, the I controller,
    ///   rejects 40 % there. The pairs keep PI.3.4: with PI.4.2 they reject 8–9 %
    ///   of their attempts on the same run (19 680 for Tsitouras).
    fn gains(self) -> (f64, f64) {
        match self {
            Scheme::Pair(_) => (0.7, 0.4),
            Scheme::Dop853 => (0.6, 0.2),
        }
    }
}

/// Buffers reused by every step.
pub(super) struct Workspace {
    scheme: Scheme,
    pub(super) n: usize,
    /// The leading states a stage's argument needs ([`System::dynamic_dim`]): the
    /// stages before the last form only these, the new state all `n`.
    pub(super) m: usize,
    pub(super) k: Vec<Vec<f64>>,
    pub(super) y1: Vec<f64>,
    pub(super) ytmp: Vec<f64>,
    /// The absolute tolerance of each state, `atol`·scale.
    pub(super) atol: Vec<f64>,
    /// The last step's scaled squared local errors (err_i / sc_i)², summed in order
    /// by [`error_norm`].
    err: Vec<f64>,
    /// The dense output of the last step: y at its start in `dense[0]`, and for
    /// [`Dense::Hairer`] its four other vectors (dop853: its seven).
    pub(super) dense: Vec<Vec<f64>>,
    /// Whether `dense` holds the last step's output (dop853 computes it on demand).
    pub(super) dense_ready: bool,
    /// The last step's size (for [`Dense::Polynomial`] and dop853).
    pub(super) h_dense: f64,
    h: f64,
    err_old: f64,
}

impl Workspace {
    fn new(scheme: Scheme, scale: &[f64], atol: f64, m: usize) -> Self {
        let n = scale.len();
        let v = || vec![0.0; n];
        Workspace {
            scheme,
            n,
            m: m.min(n),
            k: (0..scheme.stages()).map(|_| v()).collect(),
            y1: v(),
            ytmp: v(),
            atol: scale.iter().map(|s| atol * s).collect(),
            err: v(),
            dense: (0..scheme.dense()).map(|_| v()).collect(),
            dense_ready: false,
            h_dense: 0.0,
            h: 0.0,
            err_old: 1e-4,
        }
    }
}

/// An explicit Runge–Kutta 5(4) pair of seven stages, FSAL: stage s + 1 (s = 0…5)
/// at t + c[s]·h from y + h·Σ_j a[s][j]·k_j, row 6 the 5th-order solution; the
/// error estimate h·Σ_j e_j·k_j; and its dense output.
pub(super) struct Pair {
    a: [[f64; 6]; 6],
    c: [f64; 6],
    e: [f64; 7],
    dense: Dense,
}

/// A pair's continuous extension.
enum Dense {
    /// Hairer's for Dormand–Prince (dopri5's `contd5`), from these coefficients.
    Hairer([f64; 7]),
    /// y(t + θh) = y + h·Σ_j b_j(θ)·k_j with b_j(θ) = Σ_{p=1…4} r[p−1][j]·θ^p.
    Polynomial([[f64; 7]; 4]),
}

/// Dormand & Prince (1980), Hairer, Nørsett & Wanner I, Table II.5.2.
pub(super) const DP54: Pair = Pair {
    a: [
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
    ],
    c: [0.2, 0.3, 0.8, 8.0 / 9.0, 1.0, 1.0],
    e: [
        71.0 / 57600.0,
        0.0,
        -71.0 / 16695.0,
        71.0 / 1920.0,
        -17253.0 / 339200.0,
        22.0 / 525.0,
        -1.0 / 40.0,
    ],
    dense: Dense::Hairer([
        -12715105075.0 / 11282082432.0,
        0.0,
        87487479700.0 / 32700410799.0,
        -10690763975.0 / 1880347072.0,
        701980252875.0 / 199316789632.0,
        -1453857185.0 / 822651844.0,
        69997945.0 / 29380423.0,
    ]),
};

/// Tsitouras's 5th-order weights b (Tsitouras 2011, Table 1; as diffsol 0.18 and
/// OrdinaryDiffEq.jl's `Tsit5` give them).
const TSIT_B: [f64; 6] = [
    0.09646076681806523,
    0.01,
    0.4798896504144996,
    1.379008574103742,
    -3.290069515436081,
    2.324710524099774,
];

/// Tsitouras 5(4) (Tsitouras 2011; coefficients as diffsol 0.18's `tsit45`, the
/// first column from the row sums a[s][0] = c[s] − Σ_{j≥1} a[s][j]).
pub(super) const TSIT45: Pair = Pair {
    a: [
        [0.161, 0.0, 0.0, 0.0, 0.0, 0.0],
        [
            0.327 - 0.335480655492357,
            0.335480655492357,
            0.0,
            0.0,
            0.0,
            0.0,
        ],
        [
            0.9 - (-6.359448489975075 + 4.362295432869581),
            -6.359448489975075,
            4.362295432869581,
            0.0,
            0.0,
            0.0,
        ],
        [
            0.9800255409045097 - (-11.74888356406283 + 7.495539342889836 - 0.09249506636175525),
            -11.74888356406283,
            7.495539342889836,
            -0.09249506636175525,
            0.0,
            0.0,
        ],
        [
            1.0 - (-12.92096931784711 + 8.159367898576159
                - 0.071584973281401
                - 0.02826905039406838),
            -12.92096931784711,
            8.159367898576159,
            -0.071584973281401,
            -0.02826905039406838,
            0.0,
        ],
        TSIT_B,
    ],
    c: [0.161, 0.327, 0.9, 0.9800255409045097, 1.0, 1.0],
    e: [
        -0.001780011052225777,
        -0.0008164344596567469,
        0.007880878010261995,
        -0.1447110071732629,
        0.5823571654525552,
        -0.45808210592918697,
        0.015151515151515152,
    ],
    // the interpolant's b_j(θ) (OrdinaryDiffEq.jl, `Tsit5Interp`: r11 … r74)
    dense: Dense::Polynomial([
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [
            -2.763706197274826,
            0.13169999999999998,
            3.9302962368947516,
            -12.411077166933676,
            37.50931341651104,
            -27.896526289197286,
            1.5,
        ],
        [
            2.9132554618219126,
            -0.2234,
            -5.941033872131505,
            30.33818863028232,
            -88.1789048947664,
            65.09189467479366,
            -4.0,
        ],
        [
            -1.0530884977290216,
            0.1017,
            2.490627285651253,
            -16.548102889244902,
            47.37952196281928,
            -34.87065786149661,
            2.5,
        ],
    ]),
};

/// y + h·Σ_{j<S} c_j·k_j into `out`, component by component, the sum over j in
/// order from 0 (the arithmetic of accumulating one k_j at a time into a zeroed
/// vector, in one pass: no scratch vector, no bounds checks in the loop).
#[inline(always)]
fn stage_sum<const S: usize>(c: &[f64; S], k: &[Vec<f64>], y: &[f64], h: f64, out: &mut [f64]) {
    let n = out.len();
    let k: [&[f64]; S] = std::array::from_fn(|j| &k[j][..n]);
    let y = &y[..n];
    for i in 0..n {
        let mut acc = 0.0;
        for j in 0..S {
            acc += c[j] * k[j][i];
        }
        out[i] = y[i] + h * acc;
    }
}

/// Stage `s` + 1's argument y + h·Σ_{j≤s} a[s][j]·k_j (row 5: the 5th-order
/// solution) into `out`.
fn stage(a: &[f64; 6], s: usize, k: &[Vec<f64>], y: &[f64], h: f64, out: &mut [f64]) {
    /// The first `S` coefficients of a row.
    fn first<const S: usize>(a: &[f64; 6]) -> [f64; S] {
        std::array::from_fn(|j| a[j])
    }
    match s {
        0 => stage_sum(&first::<1>(a), k, y, h, out),
        1 => stage_sum(&first::<2>(a), k, y, h, out),
        2 => stage_sum(&first::<3>(a), k, y, h, out),
        3 => stage_sum(&first::<4>(a), k, y, h, out),
        4 => stage_sum(&first::<5>(a), k, y, h, out),
        _ => stage_sum(a, k, y, h, out),
    }
}

/// Weighted RMS norm of the local error h·Σ_j e_j·k_j (all states, `atol[i]` the
/// absolute tolerance of state i): each component's (err_i / sc_i)² into `err` first
/// (a loop over the components the compiler vectorises, the division too), then the
/// norm's sum in order.
#[allow(clippy::too_many_arguments)]
fn error_norm(
    e: &[f64; 7],
    k: &[Vec<f64>],
    h: f64,
    y0: &[f64],
    y1: &[f64],
    atol: &[f64],
    rtol: f64,
    err: &mut [f64],
) -> f64 {
    let n = y0.len();
    let k: [&[f64]; 7] = std::array::from_fn(|j| &k[j][..n]);
    let (y1, atol, err) = (&y1[..n], &atol[..n], &mut err[..n]);
    for i in 0..n {
        let mut acc = 0.0;
        for j in 0..7 {
            acc += e[j] * k[j][i];
        }
        let sc = atol[i] + rtol * y0[i].abs().max(y1[i].abs());
        err[i] = (acc * h / sc).powi(2);
    }
    (err.iter().fold(0.0, |s, e| s + e) / n as f64).sqrt()
}

/// Dense output of the last accepted step into `out` at θ ∈ [0, 1] (after
/// [`prepare_dense`]).
fn dense_eval(w: &Workspace, theta: f64, out: &mut [f64]) {
    let d = &w.dense;
    let pair = match w.scheme {
        Scheme::Pair(p) => p,
        Scheme::Dop853 => return dop853::dense_eval(w, theta, out),
    };
    match &pair.dense {
        Dense::Hairer(_) => {
            let (t1, n) = (1.0 - theta, w.n);
            let d: [&[f64]; 5] = std::array::from_fn(|r| &d[r][..n]);
            for (i, o) in out[..n].iter_mut().enumerate() {
                *o =
                    d[0][i] + theta * (d[1][i] + t1 * (d[2][i] + theta * (d[3][i] + t1 * d[4][i])));
            }
        }
        Dense::Polynomial(r) => {
            let b: [f64; 7] = std::array::from_fn(|j| {
                w.h_dense
                    * theta
                    * (r[0][j] + theta * (r[1][j] + theta * (r[2][j] + theta * r[3][j])))
            });
            let n = out.len();
            let k: [&[f64]; 7] = std::array::from_fn(|j| &w.k[j][..n]);
            let y0 = &d[0][..n];
            for i in 0..n {
                let mut o = y0[i];
                for j in 0..7 {
                    o += b[j] * k[j][i];
                }
                out[i] = o;
            }
        }
    }
}

/// Integrate over the restart intervals `bounds` (see [`super::run`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn run<S: System>(
    scheme: Scheme,
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
    let mut w = Workspace::new(scheme, &scale[..y.len()], o.atol, sys.dynamic_dim());
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
        let err = rk_step(&sys, w, t, h, y, o.rtol, stats);
        if o.fixed_step.is_none() {
            let q = w.scheme.exponent();
            if err > 1.0 {
                stats.rejected += 1;
                w.h = h * (0.9 * err.powf(-1.0 / q)).clamp(0.2, 1.0);
                continue;
            }
            // PI controller on accepted steps
            let (kip, kp) = w.scheme.gains();
            let e = err.max(1e-10);
            let fac = 0.9 * e.powf(-kip / q) * w.err_old.powf(kp / q);
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
                prepare_dense(&sys, w, t, y, stats);
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
        if next_sample < samples.len() && samples[next_sample] <= t_new {
            prepare_dense(&sys, w, t, y, stats);
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
        // FSAL: k[0] ← f(t_new, y) (the last stage is written again before it is
        // read)
        w.k.swap(0, w.scheme.last());
    }
    End::Done
}

/// Stages `from`…`to` of a step from (t, y) with k[0] = f(t, y) (1…last: the
/// step; after the last: dop853's dense output): stage s's argument
/// y + h·Σ_{j<s} a_sj·k_j by `stage(s, k, y, h, out)` into `ytmp` (its leading
/// `w.m` states: no rate reads the rest), the last one's (the new state, every
/// state) into `y1`, and k[s] = f(t + c(s)·h, argument).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn stages<S: System>(
    sys: &Left<S>,
    w: &mut Workspace,
    t: f64,
    h: f64,
    y: &[f64],
    range: std::ops::RangeInclusive<usize>,
    c: impl Fn(usize) -> f64,
    stage: impl Fn(usize, &[Vec<f64>], &[f64], f64, &mut [f64]),
    stats: &mut Stats,
) {
    let last = w.scheme.last();
    stats.rhs_evals += range.clone().count();
    for s in range {
        let (done, next) = w.k.split_at_mut(s);
        let (arg, len) = if s == last {
            (&mut w.y1, w.n)
        } else {
            (&mut w.ytmp, w.m)
        };
        stage(s, done, y, h, &mut arg[..len]);
        sys.rhs(t + c(s) * h, arg, &mut next[0]);
    }
}

/// The dense output of the last step made ready from (t, y), its start: a
/// 5(4) pair's is written by every step, dop853's on demand ([`dop853::prepare_dense`]).
fn prepare_dense<S: System>(
    sys: &Left<S>,
    w: &mut Workspace,
    t: f64,
    y: &[f64],
    stats: &mut Stats,
) {
    if let Scheme::Dop853 = w.scheme {
        dop853::prepare_dense(sys, w, t, y, stats);
    }
}

/// One step of the scheme; returns the error norm (∞ if the step is not finite).
fn rk_step<S: System>(
    sys: &Left<S>,
    w: &mut Workspace,
    t: f64,
    h: f64,
    y: &[f64],
    rtol: f64,
    stats: &mut Stats,
) -> f64 {
    match w.scheme {
        Scheme::Pair(p) => pair_step(p, sys, w, t, h, y, rtol, stats),
        Scheme::Dop853 => dop853::step(sys, w, t, h, y, rtol, stats),
    }
}

/// One step of a 5(4) pair; returns the error norm (∞ if the step is not finite).
#[allow(clippy::too_many_arguments)]
fn pair_step<S: System>(
    p: &'static Pair,
    sys: &Left<S>,
    w: &mut Workspace,
    t: f64,
    h: f64,
    y: &[f64],
    rtol: f64,
    stats: &mut Stats,
) -> f64 {
    let n = w.n;
    // stages 1…5 from y + h·Σ a·k into `ytmp`; row 6 (b) into `y1`, the 5th-order
    // solution, and k[6] = f(t + h, y1)
    stages(
        sys,
        w,
        t,
        h,
        y,
        1..=w.scheme.last(),
        |s| p.c[s - 1],
        |s, k, y, h, out| stage(&p.a[s - 1], s - 1, k, y, h, out),
        stats,
    );
    let err = error_norm(&p.e, &w.k, h, y, &w.y1, &w.atol, rtol, &mut w.err);
    w.dense[0].copy_from_slice(y);
    w.h_dense = h;
    if let Dense::Hairer(d) = &p.dense {
        let [_, d1, d2, d3, d4] = &mut w.dense[..] else {
            unreachable!("the workspace holds five dense vectors for a 5(4) pair")
        };
        d4.fill(0.0);
        for (d, k) in d.iter().zip(&w.k) {
            for (acc, k) in d4.iter_mut().zip(k) {
                *acc += d * k;
            }
        }
        for i in 0..n {
            let dy = w.y1[i] - y[i];
            let bsp = h * w.k[0][i] - dy;
            d1[i] = dy;
            d2[i] = bsp;
            d3[i] = dy - h * w.k[6][i] - bsp;
            d4[i] *= h;
        }
    }
    if err.is_finite() {
        err
    } else {
        f64::INFINITY
    }
}
