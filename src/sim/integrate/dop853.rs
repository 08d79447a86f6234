//! Dormand–Prince 8(5,3) (Prince & Dormand 1981; Hairer, Nørsett & Wanner I,
//! §II.10, and Hairer's `dop853.f`): twelve stages a step, the last of them
//! f(t + h, y1), which is the next step's first (so eleven new right-hand sides a
//! step and one at the new state); the error estimate Hairer combines from an
//! embedded 5th- and 3rd-order solution, err = h·‖e5‖²/√(‖e5‖² + 0.01·‖e3‖²) in
//! the weighted RMS norm, and his 7th-order continuous extension, which takes three
//! more stages, computed only in a step that has a sample or an event in it.
//!
//! For long runs resolved by accuracy, not stability (a lightly damped axial mode
//! ringing for thousands of periods at rtol ≤ 10⁻⁶), its 8th order takes about a
//! third of Tsitouras's steps for two of its right-hand sides a step.
//! Coefficients: `dop853.f` (Hairer's distribution), as SciPy's
//! `dop853_coefficients.py` transcribes them; the 3rd-order error weights are b
//! minus `bhh1…3`, computed here as there.

// The coefficients are written as `dop853.f` publishes them (30 digits), so they
// can be checked against it line by line; the compiler rounds each to nearest.
#![allow(clippy::excessive_precision)]

use super::dopri::{stages, Workspace};
use super::{Left, Stats, System};

/// The stage times c_s (s = 0…15; 12 is the new state, 13…15 the dense output's).
const C: [f64; 16] = [
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510,
    0.281649658092772603273242802490,
    0.333333333333333333333333333333,
    0.25,
    0.307692307692307692307692307692,
    0.651282051282051282051282051282,
    0.6,
    0.857142857142857142857142857142,
    1.0,
    1.0,
    0.1,
    0.2,
    0.777777777777777777777777777778,
];

/// A sparse row: (j, a_j) for the nonzero coefficients of the stages k_j it sums.
type Row<const S: usize> = [(usize, f64); S];

const A1: Row<1> = [(0, 5.26001519587677318785587544488e-2)];
const A2: Row<2> = [
    (0, 1.97250569845378994544595329183e-2),
    (1, 5.91751709536136983633785987549e-2),
];
const A3: Row<2> = [
    (0, 2.95875854768068491816892993775e-2),
    (2, 8.87627564304205475450678981324e-2),
];
const A4: Row<3> = [
    (0, 2.41365134159266685502369798665e-1),
    (2, -8.84549479328286085344864962717e-1),
    (3, 9.24834003261792003115737966543e-1),
];
const A5: Row<3> = [
    (0, 3.7037037037037037037037037037e-2),
    (3, 1.70828608729473871279604482173e-1),
    (4, 1.25467687566822425016691814123e-1),
];
const A6: Row<4> = [
    (0, 3.7109375e-2),
    (3, 1.70252211019544039314978060272e-1),
    (4, 6.02165389804559606850219397283e-2),
    (5, -1.7578125e-2),
];
const A7: Row<5> = [
    (0, 3.70920001185047927108779319836e-2),
    (3, 1.70383925712239993810214054705e-1),
    (4, 1.07262030446373284651809199168e-1),
    (5, -1.53194377486244017527936158236e-2),
    (6, 8.27378916381402288758473766002e-3),
];
const A8: Row<6> = [
    (0, 6.24110958716075717114429577812e-1),
    (3, -3.36089262944694129406857109825),
    (4, -8.68219346841726006818189891453e-1),
    (5, 2.75920996994467083049415600797e1),
    (6, 2.01540675504778934086186788979e1),
    (7, -4.34898841810699588477366255144e1),
];
const A9: Row<7> = [
    (0, 4.77662536438264365890433908527e-1),
    (3, -2.48811461997166764192642586468),
    (4, -5.90290826836842996371446475743e-1),
    (5, 2.12300514481811942347288949897e1),
    (6, 1.52792336328824235832596922938e1),
    (7, -3.32882109689848629194453265587e1),
    (8, -2.03312017085086261358222928593e-2),
];
const A10: Row<8> = [
    (0, -9.3714243008598732571704021658e-1),
    (3, 5.18637242884406370830023853209),
    (4, 1.09143734899672957818500254654),
    (5, -8.14978701074692612513997267357),
    (6, -1.85200656599969598641566180701e1),
    (7, 2.27394870993505042818970056734e1),
    (8, 2.49360555267965238987089396762),
    (9, -3.0467644718982195003823669022),
];
const A11: Row<9> = [
    (0, 2.27331014751653820792359768449),
    (3, -1.05344954667372501984066689879e1),
    (4, -2.00087205822486249909675718444),
    (5, -1.79589318631187989172765950534e1),
    (6, 2.79488845294199600508499808837e1),
    (7, -2.85899827713502369474065508674),
    (8, -8.87285693353062954433549289258),
    (9, 1.23605671757943030647266201528e1),
    (10, 6.43392746015763530355970484046e-1),
];
/// The 8th-order weights b (row 12 of A).
const B: Row<8> = [
    (0, 5.42937341165687622380535766363e-2),
    (5, 4.45031289275240888144113950566),
    (6, 1.89151789931450038304281599044),
    (7, -5.8012039600105847814672114227),
    (8, 3.1116436695781989440891606237e-1),
    (9, -1.52160949662516078556178806805e-1),
    (10, 2.01365400804030348374776537501e-1),
    (11, 4.47106157277725905176885569043e-2),
];
const A13: Row<8> = [
    (0, 5.61675022830479523392909219681e-2),
    (6, 2.53500210216624811088794765333e-1),
    (7, -2.46239037470802489917441475441e-1),
    (8, -1.24191423263816360469010140626e-1),
    (9, 1.5329179827876569731206322685e-1),
    (10, 8.20105229563468988491666602057e-3),
    (11, 7.56789766054569976138603589584e-3),
    (12, -8.298e-3),
];
const A14: Row<8> = [
    (0, 3.18346481635021405060768473261e-2),
    (5, 2.83009096723667755288322961402e-2),
    (6, 5.35419883074385676223797384372e-2),
    (7, -5.49237485713909884646569340306e-2),
    (10, -1.08347328697249322858509316994e-4),
    (11, 3.82571090835658412954920192323e-4),
    (12, -3.40465008687404560802977114492e-4),
    (13, 1.41312443674632500278074618366e-1),
];
const A15: Row<8> = [
    (0, -4.28896301583791923408573538692e-1),
    (5, -4.69762141536116384314449447206),
    (6, 7.68342119606259904184240953878),
    (7, 4.06898981839711007970213554331),
    (8, 3.56727187455281109270669543021e-1),
    (12, -1.39902416515901462129418009734e-3),
    (13, 2.9475147891527723389556272149),
    (14, -9.15095847217987001081870187138),
];

/// The 5th-order error weights (`er1…er12` of `dop853.f`).
const E5: Row<8> = [
    (0, 0.1312004499419488073250102996e-1),
    (5, -0.1225156446376204440720569753e1),
    (6, -0.4957589496572501915214079952),
    (7, 0.1664377182454986536961530415e1),
    (8, -0.3503288487499736816886487290),
    (9, 0.3341791187130174790297318841),
    (10, 0.8192320648511571246570742613e-1),
    (11, -0.2235530786388629525884427845e-1),
];
/// The 3rd-order error weights: b − (`bhh1` at k0, `bhh2` at k8, `bhh3` at k11).
const E3: Row<8> = [
    (0, B[0].1 - 0.244094488188976377952755905512),
    (5, B[1].1),
    (6, B[2].1),
    (7, B[3].1),
    (8, B[4].1 - 0.733846688281611857341361741547),
    (9, B[5].1),
    (10, B[6].1),
    (11, B[7].1 - 0.220588235294117647058823529412e-1),
];

/// The dense output's 4th…7th coefficient vectors, h·Σ_j d_rj·k_j (`dop853.f`'s
/// `d41…d716`), over the stages 0 and 5…15.
const D: [Row<12>; 4] = [
    [
        (0, -0.84289382761090128651353491142e1),
        (5, 0.56671495351937776962531783590),
        (6, -0.30689499459498916912797304727e1),
        (7, 0.23846676565120698287728149680e1),
        (8, 0.21170345824450282767155149946e1),
        (9, -0.87139158377797299206789907490),
        (10, 0.22404374302607882758541771650e1),
        (11, 0.63157877876946881815570249290),
        (12, -0.88990336451333310820698117400e-1),
        (13, 0.18148505520854727256656404962e2),
        (14, -0.91946323924783554000451984436e1),
        (15, -0.44360363875948939664310572000e1),
    ],
    [
        (0, 0.10427508642579134603413151009e2),
        (5, 0.24228349177525818288430175319e3),
        (6, 0.16520045171727028198505394887e3),
        (7, -0.37454675472269020279518312152e3),
        (8, -0.22113666853125306036270938578e2),
        (9, 0.77334326684722638389603898808e1),
        (10, -0.30674084731089398182061213626e2),
        (11, -0.93321305264302278729567221706e1),
        (12, 0.15697238121770843886131091075e2),
        (13, -0.31139403219565177677282850411e2),
        (14, -0.93529243588444783865713862664e1),
        (15, 0.35816841486394083752465898540e2),
    ],
    [
        (0, 0.19985053242002433820987653617e2),
        (5, -0.38703730874935176555105901742e3),
        (6, -0.18917813819516756882830838328e3),
        (7, 0.52780815920542364900561016686e3),
        (8, -0.11573902539959630126141871134e2),
        (9, 0.68812326946963000169666922661e1),
        (10, -0.10006050966910838403183860980e1),
        (11, 0.77771377980534432092869265740),
        (12, -0.27782057523535084065932004339e1),
        (13, -0.60196695231264120758267380846e2),
        (14, 0.84320405506677161018159903784e2),
        (15, 0.11992291136182789328035130030e2),
    ],
    [
        (0, -0.25693933462703749003312586129e2),
        (5, -0.15418974869023643374053993627e3),
        (6, -0.23152937917604549567536039109e3),
        (7, 0.35763911791061412378285349910e3),
        (8, 0.93405324183624310003907691704e2),
        (9, -0.37458323136451633156875139351e2),
        (10, 0.10409964950896230045147246184e3),
        (11, 0.29840293426660503123344363579e2),
        (12, -0.43533456590011143754432175058e2),
        (13, 0.96324553959188282948394950600e2),
        (14, -0.39177261675615439165231486172e2),
        (15, -0.14972683625798562581422125276e3),
    ],
];

/// Stages a step holds: the twelve of the step, f(t + h, y1) and the dense
/// output's three.
pub(super) const STAGES: usize = 16;
/// The stage holding f(t + h, y1), the next step's first.
pub(super) const LAST: usize = 12;
/// Vectors of the dense output: y at the step's start and the seven coefficient
/// vectors F0…F6 of the continuous extension.
pub(super) const DENSE: usize = 8;

/// Σ_j a_j·k_j[i] over a sparse row, in the row's order.
#[inline(always)]
fn row_sum<const S: usize>(row: &Row<S>, k: &[&[f64]; S], i: usize) -> f64 {
    let mut acc = 0.0;
    for j in 0..S {
        acc += row[j].1 * k[j][i];
    }
    acc
}

/// The row's stages cut to length `n`.
#[inline(always)]
fn stages_of<'a, const S: usize>(row: &Row<S>, k: &'a [Vec<f64>], n: usize) -> [&'a [f64]; S] {
    std::array::from_fn(|j| &k[row[j].0][..n])
}

/// y + h·Σ_j a_j·k_j over a sparse row into `out`, component by component.
#[inline(always)]
fn stage_sum<const S: usize>(row: &Row<S>, k: &[Vec<f64>], y: &[f64], h: f64, out: &mut [f64]) {
    let n = out.len();
    let k = stages_of(row, k, n);
    let y = &y[..n];
    for i in 0..n {
        out[i] = y[i] + h * row_sum(row, &k, i);
    }
}

/// Stage `s`'s argument y + h·Σ_{j<s} a[s][j]·k_j (s = 12: the 8th-order
/// solution) into `out`; `k` holds the stages before `s`.
fn stage(s: usize, k: &[Vec<f64>], y: &[f64], h: f64, out: &mut [f64]) {
    match s {
        1 => stage_sum(&A1, k, y, h, out),
        2 => stage_sum(&A2, k, y, h, out),
        3 => stage_sum(&A3, k, y, h, out),
        4 => stage_sum(&A4, k, y, h, out),
        5 => stage_sum(&A5, k, y, h, out),
        6 => stage_sum(&A6, k, y, h, out),
        7 => stage_sum(&A7, k, y, h, out),
        8 => stage_sum(&A8, k, y, h, out),
        9 => stage_sum(&A9, k, y, h, out),
        10 => stage_sum(&A10, k, y, h, out),
        11 => stage_sum(&A11, k, y, h, out),
        12 => stage_sum(&B, k, y, h, out),
        13 => stage_sum(&A13, k, y, h, out),
        14 => stage_sum(&A14, k, y, h, out),
        _ => stage_sum(&A15, k, y, h, out),
    }
}

/// One step from (t, y) with k[0] = f(t, y): the 8th-order solution into `w.y1`,
/// f there into k[12]; returns Hairer's error estimate (∞ if not finite).
pub(super) fn step<S: System>(
    sys: &Left<S>,
    w: &mut Workspace,
    t: f64,
    h: f64,
    y: &[f64],
    rtol: f64,
    stats: &mut Stats,
) -> f64 {
    let n = w.n;
    stages(sys, w, t, h, y, 1..=LAST, |s| C[s], stage, stats);
    w.h_dense = h;
    w.dense_ready = false;
    // E3 reads the stages E5 reads (`the_tableau_meets_its_conditions`)
    let k5 = stages_of(&E5, &w.k, n);
    let (y0, y1, atol) = (&y[..n], &w.y1[..n], &w.atol[..n]);
    let (mut e5, mut e3) = (0.0, 0.0);
    for i in 0..n {
        let sc = atol[i] + rtol * y0[i].abs().max(y1[i].abs());
        e5 += (row_sum(&E5, &k5, i) / sc).powi(2);
        e3 += (row_sum(&E3, &k5, i) / sc).powi(2);
    }
    if e5 == 0.0 && e3 == 0.0 {
        return 0.0;
    }
    let err = h.abs() * e5 / ((e5 + 0.01 * e3) * n as f64).sqrt();
    if err.is_finite() {
        err
    } else {
        f64::INFINITY
    }
}

/// The continuous extension of the last step from (t, y) (before the FSAL swap:
/// k[0] = f(t, y), k[12] = f(t + h, y1)): the three extra stages and the vectors
/// F0…F6 (Hairer's `contd8` coefficients), once a step.
pub(super) fn prepare_dense<S: System>(
    sys: &Left<S>,
    w: &mut Workspace,
    t: f64,
    y: &[f64],
    stats: &mut Stats,
) {
    if w.dense_ready {
        return;
    }
    let (n, h) = (w.n, w.h_dense);
    stages(
        sys,
        w,
        t,
        h,
        y,
        LAST + 1..=STAGES - 1,
        |s| C[s],
        stage,
        stats,
    );
    // the four rows read the same stages (`the_tableau_meets_its_conditions`)
    let kd = stages_of(&D[0], &w.k, n);
    let (k0, k12, y1) = (&w.k[0][..n], &w.k[LAST][..n], &w.y1[..n]);
    let [y_old, f0, f1, f2, f3, f4, f5, f6] = &mut w.dense[..] else {
        unreachable!("the workspace holds {DENSE} dense vectors for dop853")
    };
    for i in 0..n {
        let dy = y1[i] - y[i];
        y_old[i] = y[i];
        f0[i] = dy;
        f1[i] = h * k0[i] - dy;
        f2[i] = 2.0 * dy - h * (k12[i] + k0[i]);
        f3[i] = h * row_sum(&D[0], &kd, i);
        f4[i] = h * row_sum(&D[1], &kd, i);
        f5[i] = h * row_sum(&D[2], &kd, i);
        f6[i] = h * row_sum(&D[3], &kd, i);
    }
    w.dense_ready = true;
}

/// The continuous extension at θ ∈ [0, 1] into `out` (after [`prepare_dense`]):
/// y0 + θ(F0 + (1−θ)(F1 + θ(F2 + (1−θ)(F3 + θ(F4 + (1−θ)(F5 + θ·F6)))))).
pub(super) fn dense_eval(w: &Workspace, theta: f64, out: &mut [f64]) {
    let (t1, n) = (1.0 - theta, w.n);
    let d: [&[f64]; DENSE] = std::array::from_fn(|r| &w.dense[r][..n]);
    for (i, o) in out[..n].iter_mut().enumerate() {
        let mut v = d[7][i] * theta;
        v = (v + d[6][i]) * t1;
        v = (v + d[5][i]) * theta;
        v = (v + d[4][i]) * t1;
        v = (v + d[3][i]) * theta;
        v = (v + d[2][i]) * t1;
        v = (v + d[1][i]) * theta;
        *o = v + d[0][i];
    }
}

#[cfg(test)]
mod tests {
    use super::super::{run, End, Extra, Method, Options};
    use super::*;

    /// The pendulum θ'' = −sin θ: nonlinear, not stiff, every elementary
    /// differential of the order conditions present.
    struct Pendulum;

    impl System for Pendulum {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = y[1];
            dy[1] = -y[0].sin();
        }
        fn jacobian_times(&self, _t: f64, y: &[f64], v: &[f64], out: &mut [f64]) {
            out[0] = v[1];
            out[1] = -y[0].cos() * v[0];
        }
        fn jacobian(&self, _t: f64, y: &[f64], jac: &mut [f64]) {
            jac.copy_from_slice(&[0.0, 1.0, -y[0].cos(), 0.0]);
        }
        fn n_params(&self) -> usize {
            0
        }
        fn param_jacobian(&self, _t: f64, _y: &[f64], _dfdp: &mut [f64]) {}
        fn sensitivity_rate(&self, _t: f64, _y: &[f64], _s: &[f64], _k: usize, _o: &mut [f64]) {}
        fn initial_sensitivity(&self, _out: &mut [f64]) {}
    }

    /// θ at the end (t = 3.6) and at the sample t = 1.5 (inside a step: the
    /// continuous extension) from θ = 1 at rest, at the fixed step `h` (or at
    /// `rtol` when h is None).
    fn pendulum(h: Option<f64>, rtol: f64) -> (f64, f64, usize) {
        let o = Options {
            rtol,
            atol: rtol,
            h_max: 1.0,
            h_init: 1e-3,
            max_steps: 1_000_000,
            fixed_step: h,
        };
        let mut y = [1.0, 0.0];
        let mut at = f64::NAN;
        let mut stats = Default::default();
        let end = run(
            &Pendulum,
            Method::Dop853,
            &o,
            &[1.0, 1.0],
            &[0.0, 3.6],
            &mut y,
            &[1.5],
            Extra::None,
            &mut |_, y, _| at = y[0],
            &mut |_, _| {},
            None,
            &mut |_, _| {},
            &mut stats,
        );
        assert_eq!(end, End::Done);
        (y[0], at, stats.steps)
    }

    /// The order: at fixed steps h = 0.6 and 0.2 (6 and 18 steps; t = 1.5 is the
    /// middle of a step at both) the end state's error falls by at least 3^7.5
    /// (an 8th-order method: measured 3^9.3, its leading error terms being small
    /// by design at these steps; a wrong coefficient drops the order to ≤ 5) and
    /// the continuous extension's by at least 3^6.5 (7th order: measured 3^8.2);
    /// the reference is the same method at h = 0.0125, 10⁸ times more accurate.
    /// And adaptive: the error follows the tolerance (within 10× of rtol at 10⁻⁶
    /// and 10⁻¹⁰ on this O(1) state).
    #[test]
    fn dop853_is_8th_order_and_its_extension_7th() {
        let (y_ref, at_ref, _) = pendulum(Some(0.0125), 1e-6);
        let err = |h: f64| {
            let (y, at, _) = pendulum(Some(h), 1e-6);
            ((y - y_ref).abs(), (at - at_ref).abs())
        };
        let ((e1, d1), (e2, d2)) = (err(0.6), err(0.2));
        let order = (e1 / e2).ln() / 3f64.ln();
        assert!(order > 7.5, "order {order} ({e1:e}, {e2:e})");
        let dense = (d1 / d2).ln() / 3f64.ln();
        assert!(
            dense > 6.5,
            "continuous extension: order {dense} ({d1:e}, {d2:e})"
        );
        for rtol in [1e-6, 1e-10] {
            let (y, at, steps) = pendulum(None, rtol);
            assert!(
                (y - y_ref).abs() < 10.0 * rtol,
                "rtol {rtol:e}: {y} vs {y_ref}"
            );
            assert!(
                (at - at_ref).abs() < 10.0 * rtol,
                "rtol {rtol:e}: {at} vs {at_ref}"
            );
            assert!(steps < 200, "{steps} steps at rtol {rtol:e}");
        }
    }

    /// The order conditions the tableau must meet to the rounding of its
    /// coefficients: Σ b = 1, Σ b·c^(q−1) = 1/q for q ≤ 8 (the quadrature
    /// conditions of order 8), every row's sum is its c (the stages at their
    /// times), and the error weights annihilate the constants (Σ e = 0).
    #[test]
    fn the_tableau_meets_its_conditions() {
        let rows: [&[(usize, f64)]; 15] = [
            &A1, &A2, &A3, &A4, &A5, &A6, &A7, &A8, &A9, &A10, &A11, &B, &A13, &A14, &A15,
        ];
        for (s, row) in rows.iter().enumerate() {
            let sum: f64 = row.iter().map(|r| r.1).sum();
            let c = C[s + 1];
            assert!(
                (sum - c).abs() < 1e-13 * 60.0,
                "row {}: Σa = {sum}, c = {c}",
                s + 1
            );
        }
        for q in 1..=8 {
            let sum: f64 = B.iter().map(|&(j, b)| b * C[j].powi(q - 1)).sum();
            assert!(
                (sum - 1.0 / q as f64).abs() < 1e-14,
                "Σ b·c^{} = {sum}, want 1/{q}",
                q - 1
            );
        }
        for e in [&E5, &E3] {
            let sum: f64 = e.iter().map(|r| r.1).sum();
            assert!(sum.abs() < 1e-14, "Σ e = {sum}");
        }
        // the error estimate and the dense output read one set of stages per kind
        let stages = |row: &[(usize, f64)]| row.iter().map(|r| r.0).collect::<Vec<_>>();
        assert_eq!(stages(&E3), stages(&E5));
        for d in &D[1..] {
            assert_eq!(stages(d), stages(&D[0]));
        }
    }
}
