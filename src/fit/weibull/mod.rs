//! Weibull analysis of a breakdown series (docs/breakdown.md): maximum likelihood
//! with right censoring, rank regression with a named plotting position, the
//! optional threshold, covariates (α = C·h^a·λ^b with a common β), electrode areas
//! by the weakest-link law, standard errors from the observed information, Fisher
//! and likelihood-ratio bounds, percentiles and a goodness-of-fit test.
//!
//! Covariates follow the power law that Huang, Shian, Diebold, Suo & Clarke 2012
//! (Appl. Phys. Lett. 101:122905, doi:10.1063/1.4754549) found for the breakdown
//! of VHB, E_B = 51·h^−0.25·λ^0.63.
//!
//! The model (IEEE Std 930-2004, IEC 62539:2007): F(E) = 1 − exp[−(E/α)^β] at the
//! reference electrode area A₀; a specimen of area A has F_A(E) = 1 − exp[−(A/A₀)(E/α)^β]
//! (the weakest link: independent flaws, hazard additive over area; Weibull 1951,
//! J. Appl. Mech. 18:293; IEEE 930 §6.5), so α_A = α·(A₀/A)^(1/β).

mod gof;
mod likelihood;
mod rank;
mod threshold;

use crate::fit::Status;
use crate::material::breakdown::Weibull;
use likelihood::{Data, Hold, Point, LOC};
use std::fmt;

/// χ²₁(0.95) = 3.841459: the likelihood-ratio bounds are where the profile
/// log-likelihood is 3.841459/2 below its maximum (Meeker & Escobar 1998,
/// *Statistical Methods for Reliability Data*, §8.3).
pub const CHI2_1_95: f64 = 3.841_458_820_694_124;
/// z₀.₉₇₅ = 1.959964: two-sided 95 % normal quantile of the Fisher bounds.
pub const Z_975: f64 = 1.959_963_984_540_054;

/// One specimen of a breakdown series, in SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Specimen {
    /// Breakdown field, or the highest field reached by a survivor (V/m).
    pub field: f64,
    /// The specimen did not break down up to `field` (right-censored).
    pub survived: bool,
    /// Electrode area (m²), if known.
    pub area: Option<f64>,
    /// Thickness (m), if known (a covariate).
    pub thickness: Option<f64>,
    /// Prestretch (1), if known (a covariate).
    pub prestretch: Option<f64>,
}

impl Specimen {
    /// A specimen with only a field.
    pub fn new(field: f64, survived: bool) -> Self {
        Specimen {
            field,
            survived,
            area: None,
            thickness: None,
            prestretch: None,
        }
    }
}

/// The estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// Maximum likelihood with right censoring.
    Mle,
    /// Rank regression of y = ln(−ln(1 − F)) on x = ln E.
    Rry,
    /// Rank regression of x = ln E on y (Abernethy's recommendation).
    Rrx,
}

/// Plotting position F of the breakdown of adjusted rank i among n specimens.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Positions {
    /// Bernard's approximation to the median rank, (i − 0.3)/(n + 0.4) (Bernard &
    /// Bos-Levenbach 1953; Abernethy 2006 §2.15; Minitab's and Weibull++'s default).
    Bernard,
    /// Exact median rank: the median of the i-th order statistic of n uniforms,
    /// I⁻¹₀.₅(i, n − i + 1) (inverse regularized incomplete beta; Johnson 1964).
    Exact,
    /// (i − 0.44)/(n + 0.25): IEEE Std 930-2004 §6.1.2 (and IEC 62539) approximation.
    Ieee930,
}

/// A covariate of the characteristic field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Covariate {
    /// Film thickness h (m).
    Thickness,
    /// Prestretch λ (1).
    Prestretch,
}

macro_rules! named {
    ($t:ty, $what:literal, $($v:path => $n:literal),+) => {
        impl $t {
            /// The name used by the CLI and the outputs.
            pub fn name(self) -> &'static str {
                match self { $($v => $n),+ }
            }
            /// Every value, in the order of the help text.
            pub const ALL: &'static [$t] = &[$($v),+];
        }
        impl std::str::FromStr for $t {
            type Err = crate::Error;
            fn from_str(s: &str) -> crate::Result<Self> {
                match s.trim().to_ascii_lowercase().as_str() {
                    $($n => Ok($v),)+
                    _ => Err(crate::Error::settings(format!("unknown {} '{s}'", $what))
                        .with_hint(format!("use one of: {}", [$($n),+].join(", ")))),
                }
            }
        }
        impl fmt::Display for $t {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str(self.name())
            }
        }
    };
}
named!(Method, "method", Method::Mle => "mle", Method::Rry => "rry", Method::Rrx => "rrx");
named!(Positions, "plotting position", Positions::Bernard => "bernard", Positions::Exact => "exact", Positions::Ieee930 => "ieee930");
named!(Covariate, "covariate", Covariate::Thickness => "thickness", Covariate::Prestretch => "prestretch");

impl Positions {
    /// F for the (adjusted, possibly fractional) rank `i` of `n` specimens.
    pub fn position(self, i: f64, n: f64) -> f64 {
        match self {
            Positions::Bernard => (i - 0.3) / (n + 0.4),
            Positions::Ieee930 => (i - 0.44) / (n + 0.25),
            Positions::Exact => statrs::function::beta::inv_beta_reg(i, n - i + 1.0, 0.5),
        }
    }
}

impl Covariate {
    /// The SI unit of the covariate.
    pub fn unit(self) -> &'static str {
        match self {
            Covariate::Thickness => "m",
            Covariate::Prestretch => "1",
        }
    }
    fn of(self, s: &Specimen) -> Option<f64> {
        match self {
            Covariate::Thickness => s.thickness,
            Covariate::Prestretch => s.prestretch,
        }
    }
}

/// What to fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Settings {
    /// Estimator.
    pub method: Method,
    /// Plotting position (rank regression, and the probability plot of every fit).
    pub positions: Positions,
    /// Fit a threshold γ (three-parameter Weibull; MLE only).
    pub threshold: bool,
    /// Covariates of α (MLE only).
    pub covariates: Vec<Covariate>,
    /// Reference electrode area A₀ (m²) of α; None: the specimens' common area,
    /// else their median area (said in the warnings).
    pub reference_area: Option<f64>,
    /// Reference thickness (m) of α with the thickness covariate; None: the
    /// geometric mean of the specimens'.
    pub reference_thickness: Option<f64>,
    /// Reference prestretch of α with the prestretch covariate; None: the
    /// geometric mean of the specimens'.
    pub reference_prestretch: Option<f64>,
    /// Likelihood-ratio bounds also for [`LR_TABLE_BELOW`] breakdowns or more,
    /// where the table shows Fisher's: each LR bound is a profile of ≈ 10 inner
    /// maximisations over the data, most of a large series' fit time (10⁴
    /// specimens: ≈ 5 ms with, ≈ 0.5 ms without), so by default they are computed
    /// only where shown.
    pub all_lr_bounds: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            method: Method::Mle,
            positions: Positions::Bernard,
            threshold: false,
            covariates: Vec::new(),
            reference_area: None,
            reference_thickness: None,
            reference_prestretch: None,
            all_lr_bounds: false,
        }
    }
}

/// Which 95 % bounds a table shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoundKind {
    /// Profile likelihood-ratio bounds.
    LikelihoodRatio,
    /// Fisher-matrix (normal, on the log scale for positive quantities) bounds.
    Fisher,
}

impl BoundKind {
    /// `likelihood-ratio` or `fisher`.
    pub fn name(self) -> &'static str {
        match self {
            BoundKind::LikelihoodRatio => "likelihood-ratio",
            BoundKind::Fisher => "fisher",
        }
    }
}

/// An estimate in SI with its standard error and both kinds of 95 % bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Value.
    pub value: f64,
    /// Standard error from the observed information (delta method), if defined.
    pub std_error: Option<f64>,
    /// Fisher 95 % bounds.
    pub fisher95: Option<(f64, f64)>,
    /// Likelihood-ratio 95 % bounds (MLE fits without a threshold).
    pub lr95: Option<(f64, f64)>,
}

impl Estimate {
    /// The bounds of the given kind, falling back to Fisher's when those are missing.
    pub fn bounds(&self, kind: BoundKind) -> Option<(f64, f64)> {
        match kind {
            BoundKind::LikelihoodRatio => self.lr95.or(self.fisher95),
            BoundKind::Fisher => self.fisher95,
        }
    }
}

/// A covariate exponent of α = C·h^a·λ^b.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exponent {
    /// Which covariate.
    pub covariate: Covariate,
    /// The exponent (1).
    pub estimate: Estimate,
    /// The reference value α is given at (SI).
    pub reference: f64,
}

/// A goodness-of-fit test of a straight Weibull plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Goodness {
    /// The test, named with its source.
    pub test: String,
    /// The statistic.
    pub statistic: f64,
    /// Its 5 % critical value (reject a straight plot beyond it).
    pub critical5: f64,
    /// p-value, when the test gives one.
    pub p_value: Option<f64>,
    /// The plot is consistent with one Weibull population at the 5 % level.
    pub straight: bool,
}

/// A specimen on the probability plot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlotPoint {
    /// Index of the specimen in the input.
    pub specimen: usize,
    /// Field (V/m).
    pub field: f64,
    /// Plotting position F (None for a survivor: it has no rank of its own).
    pub probability: Option<f64>,
    /// The specimen survived.
    pub survived: bool,
}

/// A percentile of the breakdown field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Percentile {
    /// Probability p.
    pub p: f64,
    /// Electrode area (m²) it applies to (None: the series has no area).
    pub area: Option<f64>,
    /// E_p (V/m) with σ and bounds.
    pub estimate: Estimate,
}

/// A refusal of the data or of the settings.
#[derive(Debug, Clone, PartialEq)]
pub enum WeibullError {
    /// A field, area, thickness or prestretch that is not a positive finite number.
    NotPositive {
        /// Specimen index.
        specimen: usize,
        /// Which quantity.
        what: &'static str,
        /// The value.
        value: f64,
    },
    /// A value needed for the fit is missing on a specimen.
    Missing {
        /// Specimen index.
        specimen: usize,
        /// Which quantity.
        what: &'static str,
    },
    /// No breakdown in the series.
    AllSurvived {
        /// Specimens.
        n: usize,
    },
    /// Fewer than two breakdowns.
    TooFewBreakdowns {
        /// Breakdowns.
        failures: usize,
    },
    /// Every breakdown at one field: no spread, β unbounded.
    Degenerate {
        /// The field (V/m).
        field: f64,
        /// Breakdowns.
        failures: usize,
    },
    /// A covariate that does not vary in the series.
    ConstantCovariate {
        /// Which.
        covariate: Covariate,
        /// Its value.
        value: f64,
    },
    /// Settings that do not go together.
    Unsupported(String),
}

impl WeibullError {
    /// The specimen (index into the input) the error is about, if one.
    pub fn specimen(&self) -> Option<usize> {
        match self {
            WeibullError::NotPositive { specimen, .. } | WeibullError::Missing { specimen, .. } => {
                Some(*specimen)
            }
            _ => None,
        }
    }

    /// What to do about it.
    pub fn hint(&self) -> &'static str {
        match self {
            WeibullError::NotPositive { .. } => "every field, area, thickness and prestretch must be a positive number",
            WeibullError::Missing { .. } => "give the value on every row, or for all specimens by its flag",
            WeibullError::AllSurvived { .. } => "a series needs breakdowns: raise the rig's limit or test more specimens",
            WeibullError::TooFewBreakdowns { .. } => "a Weibull fit needs at least two breakdowns (IEEE 930 asks for ten or more)",
            WeibullError::Degenerate { .. } => "the field steps are too coarse to resolve the spread: use finer steps, or report the single field",
            WeibullError::ConstantCovariate { .. } => "drop the covariate: a constant value carries no information on its exponent",
            WeibullError::Unsupported(_) => "rank regression fits one area without threshold or covariates (use --method mle); see docs/breakdown.md",
        }
    }
}

impl fmt::Display for WeibullError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            WeibullError::NotPositive { specimen, what, value } => {
                write!(f, "specimen {}: {what} {value} is not a positive finite number", specimen + 1)
            }
            WeibullError::Missing { specimen, what } => {
                write!(f, "specimen {}: no {what}", specimen + 1)
            }
            WeibullError::AllSurvived { n } => {
                write!(f, "every one of the {n} specimens survived: no breakdown to fit")
            }
            WeibullError::TooFewBreakdowns { failures } => {
                write!(f, "{failures} breakdown(s): a Weibull fit needs at least two")
            }
            WeibullError::Degenerate { field, failures } => write!(
                f,
                "degenerate series: all {failures} breakdowns at one field, {field} V/m (the shape β is unbounded)"
            ),
            WeibullError::ConstantCovariate { covariate, value } => write!(
                f,
                "covariate {covariate} is constant in the series ({value} {})",
                covariate.unit()
            ),
            WeibullError::Unsupported(s) => f.write_str(s),
        }
    }
}

impl std::error::Error for WeibullError {}

impl From<WeibullError> for crate::Error {
    fn from(e: WeibullError) -> Self {
        let hint = e.hint();
        crate::Error::settings(e.to_string()).with_hint(hint)
    }
}

/// A fitted Weibull distribution of a breakdown series.
#[derive(Debug, Clone)]
pub struct WeibullFit {
    /// Estimator.
    pub method: Method,
    /// Plotting position of the rank regression (None for MLE).
    pub positions: Option<Positions>,
    /// Plotting position of `plot`.
    pub plot_positions: Positions,
    /// Specimens, breakdowns, survivors.
    pub n: usize,
    /// Breakdowns.
    pub failures: usize,
    /// Survivors (right-censored).
    pub survived: usize,
    /// α (V/m) at the reference area (and reference covariates).
    pub alpha: Estimate,
    /// β (1).
    pub beta: Estimate,
    /// Small-sample unbiased β, if defined for the method and data.
    pub beta_unbiased: Option<f64>,
    /// How `beta_unbiased` was computed.
    pub beta_unbiased_method: String,
    /// Threshold γ (V/m), three-parameter fits only.
    pub threshold: Option<Estimate>,
    /// Covariate exponents with their reference values.
    pub exponents: Vec<Exponent>,
    /// Parameter names in the order of `correlation`: alpha, beta, the exponents'
    /// covariate names, threshold.
    pub parameter_names: Vec<String>,
    /// Correlation matrix of the estimates (None when the information is singular).
    pub correlation: Option<Vec<Vec<f64>>>,
    /// Log-likelihood at the estimates (of the fields in V/m).
    pub log_likelihood: f64,
    /// Reference electrode area A₀ (m²) of α.
    pub reference_area: Option<f64>,
    /// The bounds a table shows (docs/breakdown.md: likelihood-ratio for MLE fits
    /// with fewer than [`LR_TABLE_BELOW`] breakdowns, else Fisher).
    pub bounds: BoundKind,
    /// Goodness of fit of a straight Weibull plot (None when no test applies).
    pub goodness: Option<Goodness>,
    /// Overall status.
    pub status: Status,
    /// Everything worth reading.
    pub warnings: Vec<String>,
    /// Every specimen on the probability plot, in field order.
    pub plot: Vec<PlotPoint>,
    /// Newton iterations of the maximum likelihood fit.
    pub iterations: usize,
    model: Model,
}

/// The tables show likelihood-ratio bounds below this many breakdowns; above, the
/// two kinds agree within a few per cent of the interval's width and Fisher's are
/// shown (docs/breakdown.md, "Bounds").
pub const LR_TABLE_BELOW: usize = 100;

/// What the public numbers are computed from: the normalised data, the natural
/// parameters θ = (u, exponents..., β[, γ]) and their covariance.
#[derive(Debug, Clone)]
struct Model {
    data: Data,
    /// E_ref (V/m): x = ln(E/E_ref).
    scale: f64,
    point: Point,
    gamma: Option<f64>,
    /// Covariance of (c_0..c_{loc−1}, β[, γ]).
    cov: Option<Vec<Vec<f64>>>,
    /// The maximum-likelihood fit (for LR bounds); None for rank regression and
    /// threshold fits.
    lr_max: Option<f64>,
}

/// Fit a breakdown series.
pub fn fit(specimens: &[Specimen], settings: &Settings) -> Result<WeibullFit, WeibullError> {
    let n = specimens.len();
    for (i, s) in specimens.iter().enumerate() {
        positive(i, "field", Some(s.field))?;
        positive(i, "area", s.area)?;
        positive(i, "thickness", s.thickness)?;
        positive(i, "prestretch", s.prestretch)?;
    }
    let failures = specimens.iter().filter(|s| !s.survived).count();
    if failures == 0 {
        return Err(WeibullError::AllSurvived { n });
    }
    if failures < 2 {
        return Err(WeibullError::TooFewBreakdowns { failures });
    }
    let first = specimens
        .iter()
        .find(|s| !s.survived)
        .map_or(0.0, |s| s.field);
    if specimens.iter().all(|s| s.survived || s.field == first) {
        return Err(WeibullError::Degenerate {
            field: first,
            failures,
        });
    }
    if settings.method != Method::Mle && (settings.threshold || !settings.covariates.is_empty()) {
        return Err(WeibullError::Unsupported(format!(
            "method {} fits neither a threshold nor covariates",
            settings.method
        )));
    }
    if settings.threshold && !settings.covariates.is_empty() {
        return Err(WeibullError::Unsupported(
            "a threshold and covariates together are not supported".into(),
        ));
    }
    let mut warnings = Vec::new();

    // Areas: exposure w_i = A_i/A₀.
    let (lnw, reference_area) = exposures(specimens, settings.reference_area, &mut warnings)?;
    let varying_area = lnw.iter().any(|&l| l != lnw[0]);
    if settings.method != Method::Mle && varying_area {
        return Err(WeibullError::Unsupported(format!(
            "method {} needs one electrode area for every specimen (the ranks pool the specimens)",
            settings.method
        )));
    }

    // Covariates: z = (1, ln(v/v_ref)...).
    let mut z = vec![[0.0; LOC]; n];
    let mut references = Vec::new();
    for (j, &cov) in settings.covariates.iter().enumerate() {
        if j + 1 >= LOC || settings.covariates[..j].contains(&cov) {
            return Err(WeibullError::Unsupported(format!(
                "covariates: each of {} at most once",
                Covariate::ALL
                    .iter()
                    .map(|c| c.name())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        let mut logs = Vec::with_capacity(n);
        for (i, s) in specimens.iter().enumerate() {
            let v = cov.of(s).ok_or(WeibullError::Missing {
                specimen: i,
                what: cov.name(),
            })?;
            logs.push(v.ln());
        }
        let (lo, hi) = logs
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        if hi - lo <= 1e-12 {
            return Err(WeibullError::ConstantCovariate {
                covariate: cov,
                value: lo.exp(),
            });
        }
        let stated = match cov {
            Covariate::Thickness => settings.reference_thickness,
            Covariate::Prestretch => settings.reference_prestretch,
        };
        if let Some(v) = stated {
            if !(v.is_finite() && v > 0.0) {
                return Err(WeibullError::Unsupported(format!(
                    "reference {cov} {v} is not a positive number"
                )));
            }
        }
        let reference = stated.unwrap_or_else(|| (logs.iter().sum::<f64>() / n as f64).exp());
        for i in 0..n {
            z[i][j + 1] = logs[i] - reference.ln();
        }
        references.push((cov, reference));
    }
    for zi in z.iter_mut() {
        zi[0] = 1.0;
    }

    // Normalised data.
    let scale = (specimens
        .iter()
        .filter(|s| !s.survived)
        .map(|s| s.field.ln())
        .sum::<f64>()
        / failures as f64)
        .exp();
    let data = Data {
        x: specimens.iter().map(|s| (s.field / scale).ln()).collect(),
        fail: specimens
            .iter()
            .map(|s| if s.survived { 0.0 } else { 1.0 })
            .collect(),
        lnw,
        z,
        loc: 1 + settings.covariates.len(),
        r: failures as f64,
    };

    // Probability plot: field order, breakdowns before survivors at a tie.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| {
        specimens[a]
            .field
            .total_cmp(&specimens[b].field)
            .then(specimens[a].survived.cmp(&specimens[b].survived))
    });
    let failed: Vec<bool> = specimens.iter().map(|s| !s.survived).collect();
    let ranked = rank::positions(&order, &failed, settings.positions);
    let mut probability = vec![None; n];
    for &(i, f) in &ranked {
        probability[i] = Some(f);
    }
    let plot: Vec<PlotPoint> = order
        .iter()
        .map(|&i| PlotPoint {
            specimen: i,
            field: specimens[i].field,
            probability: probability[i],
            survived: specimens[i].survived,
        })
        .collect();

    // Rank regression: the estimate of rrx/rry, and the MLE's start.
    let rr_points = |pos: &[(usize, f64)]| -> Vec<(f64, f64)> {
        pos.iter()
            .map(|&(i, f)| (data.x[i], (-(-f).ln_1p()).ln()))
            .collect()
    };
    let on_x = settings.method == Method::Rrx;
    let rr = rank::regression(&rr_points(&ranked), on_x)
        // The plot is referred to the specimens' (common) area: α at A₀ is
        // α_A·(A/A₀)^(1/β), i.e. u₀ = u_A + ln w/β.
        .map(|(u, b)| (u + data.lnw[0] / b, b));
    let start = match rr {
        Some((u, b)) => Point {
            c: [u, 0.0, 0.0],
            beta: b,
        },
        None => Point {
            c: [0.0; LOC],
            beta: 1.0,
        },
    };
    let mut status = Status::Ok;
    let (mle, iterations) = match data.maximize(start, Hold::Nothing, 0.0) {
        Ok(m) => (m, m.iterations),
        Err(e) => {
            warnings.push(format!(
                "the maximum-likelihood fit did not converge in {} Newton iterations",
                e.iterations
            ));
            status = Status::NotConverged;
            (
                likelihood::Maximum {
                    point: start,
                    loglik: data.loglik(&start, 0.0),
                    held_slope: 0.0,
                    iterations: e.iterations,
                },
                e.iterations,
            )
        }
    };

    let mle_point = mle.point;
    let mut model = Model {
        data,
        scale,
        point: mle.point,
        gamma: None,
        cov: None,
        lr_max: None,
    };
    let mut positions_named = None;
    match settings.method {
        Method::Mle => {
            if settings.threshold {
                threshold::fit(&mut model, specimens, &mut warnings, &mut status);
            } else if status == Status::Ok && (failures < LR_TABLE_BELOW || settings.all_lr_bounds)
            {
                model.lr_max = Some(mle.loglik);
            }
        }
        Method::Rry | Method::Rrx => {
            let Some((u, b)) = rr else {
                return Err(WeibullError::Degenerate {
                    field: first,
                    failures,
                });
            };
            model.point = Point {
                c: [u, 0.0, 0.0],
                beta: b,
            };
            positions_named = Some(settings.positions);
        }
    }
    model.cov = model.covariance();
    if model.cov.is_none() {
        warnings.push("the information matrix is singular: no standard errors".into());
        status = Status::IllPosed;
    }

    let loc = model.data.loc;
    let alpha = model.estimate_log(Hold::Loc(0), 0.0);
    let beta = model.estimate_beta();
    let exponents: Vec<Exponent> = references
        .iter()
        .enumerate()
        .map(|(j, &(covariate, reference))| Exponent {
            covariate,
            estimate: model.estimate_linear(Hold::Loc(j + 1)),
            reference,
        })
        .collect();
    let threshold = model.gamma.map(|g| {
        let se = model.cov.as_ref().map(|c| c[loc + 1][loc + 1].sqrt());
        Estimate {
            value: g,
            std_error: se,
            fisher95: se.map(|s| (g - Z_975 * s, g + Z_975 * s)),
            lr95: None,
        }
    });
    let mut parameter_names = vec!["alpha".to_string(), "beta".to_string()];
    parameter_names.extend(references.iter().map(|(c, _)| c.name().to_string()));
    if model.gamma.is_some() {
        parameter_names.push("threshold".into());
    }
    let correlation = model.correlation();

    let r = failures as f64;
    let (beta_unbiased, beta_unbiased_method) = match settings.method {
        Method::Mle if failures > 2 && model.gamma.is_none() => (
            Some(beta.value * (r - 2.0) / (r - 0.68)),
            if failures == n {
                "Ross 1994 (IEEE TDEI 1(2):247): β·(n − 2)/(n − 0.68)".to_string()
            } else {
                "Ross 1994's β·(r − 2)/(r − 0.68) with r the breakdowns in place of n (an approximation for censored data: the bias of the censored MLE is governed by the number of breakdowns)".to_string()
            },
        ),
        Method::Mle if model.gamma.is_some() => (None, "not defined for a threshold fit".into()),
        Method::Mle => (None, "needs more than two breakdowns".into()),
        _ => (
            None,
            "Ross's factor is for maximum likelihood; none for rank regression".into(),
        ),
    };

    let goodness = gof::test(&model.data, &mle_point);
    if let Some(g) = &goodness {
        if !g.straight {
            warnings.push(format!(
                "the Weibull plot is not straight: {} = {:.3} beyond its 5 % critical value {:.3} (two populations, defects, or a threshold?)",
                g.test, g.statistic, g.critical5
            ));
        }
    }
    let bounds = if model.lr_max.is_some() && failures < LR_TABLE_BELOW {
        BoundKind::LikelihoodRatio
    } else {
        BoundKind::Fisher
    };
    // IEEE 930 asks for at least 10 specimens; with survivors the information is
    // in the breakdowns, so a censored series counts those.
    if failures < 10 {
        let few = match n - failures {
            0 => format!("only {n} specimens (IEEE 930 asks for at least 10)"),
            survived => format!(
                "only {failures} breakdowns ({n} specimens, {survived} survived; IEEE 930 asks for at least 10, and with survivors the breakdowns carry the information)"
            ),
        };
        match beta.bounds(bounds) {
            Some((lo, hi)) => warnings.push(format!(
                "{few}: β's 95 % interval is {lo:.3}..{hi:.3} ({} bounds), a factor {:.2} wide",
                bounds.name(),
                hi / lo
            )),
            None => warnings.push(few),
        }
    }
    if status == Status::Ok && !warnings.is_empty() {
        status = Status::Warning;
    }

    Ok(WeibullFit {
        method: settings.method,
        positions: positions_named,
        plot_positions: settings.positions,
        n,
        failures,
        survived: n - failures,
        log_likelihood: model.loglik_si(),
        alpha,
        beta,
        beta_unbiased,
        beta_unbiased_method,
        threshold,
        exponents,
        parameter_names,
        correlation,
        reference_area,
        bounds,
        goodness,
        status,
        warnings,
        plot,
        iterations,
        model,
    })
}

fn positive(specimen: usize, what: &'static str, v: Option<f64>) -> Result<(), WeibullError> {
    match v {
        Some(value) if !(value.is_finite() && value > 0.0) => Err(WeibullError::NotPositive {
            specimen,
            what,
            value,
        }),
        _ => Ok(()),
    }
}

/// ln(A_i/A₀) per specimen and A₀ (module docs): A₀ is the stated reference area,
/// else the specimens' common area, else their median area (a warning says so).
fn exposures(
    specimens: &[Specimen],
    reference: Option<f64>,
    warnings: &mut Vec<String>,
) -> Result<(Vec<f64>, Option<f64>), WeibullError> {
    if let Some(a) = reference {
        if !(a.is_finite() && a > 0.0) {
            return Err(WeibullError::Unsupported(format!(
                "reference area {a} m² is not a positive number"
            )));
        }
    }
    let with = specimens.iter().filter(|s| s.area.is_some()).count();
    if with == 0 {
        return match reference {
            Some(_) => Err(WeibullError::Missing {
                specimen: 0,
                what: "area (a reference area needs the specimens' areas)",
            }),
            None => Ok((vec![0.0; specimens.len()], None)),
        };
    }
    if let Some(i) = specimens.iter().position(|s| s.area.is_none()) {
        return Err(WeibullError::Missing {
            specimen: i,
            what: "area (other specimens have one)",
        });
    }
    let areas: Vec<f64> = specimens.iter().filter_map(|s| s.area).collect();
    let a0 = match reference {
        Some(a) => a,
        None if areas.iter().all(|&a| a == areas[0]) => areas[0],
        None => {
            let mut sorted = areas.clone();
            sorted.sort_by(f64::total_cmp);
            let a = sorted[(sorted.len() - 1) / 2];
            warnings.push(format!(
                "the specimens' electrode areas differ: α is given at their median area, {a:e} m²"
            ));
            a
        }
    };
    Ok((areas.iter().map(|&a| (a / a0).ln()).collect(), Some(a0)))
}

impl Model {
    /// Number of natural parameters: location coefficients, β, γ.
    fn dim(&self) -> usize {
        self.data.loc + 1 + usize::from(self.gamma.is_some())
    }

    /// The covariance of the natural parameters: the inverse observed information.
    /// The information is that of (α, β), as `reliability` and Weibull++ take it,
    /// carried to u = ln α: −ℓ_αα·α² = −ℓ_uu + ℓ_u. At a maximum ℓ_u = 0 and the
    /// two agree; at a rank-regression estimate ℓ_u ≠ 0 and this is the convention
    /// of the references (tests/weibull.rs, `agrees_with_the_reliability_package`).
    fn covariance(&self) -> Option<Vec<Vec<f64>>> {
        let mut info = match self.gamma {
            Some(g) => threshold::information(self, g),
            None => self.data.information(&self.point),
        };
        if self.gamma.is_none() {
            info[0][0] += self.data.held_derivative(&self.point, Hold::Loc(0), 0.0);
        }
        let m = info.len();
        let mat = nalgebra::DMatrix::from_fn(m, m, |i, j| info[i][j]);
        let inv = mat.cholesky()?.inverse();
        let out: Vec<Vec<f64>> = (0..m)
            .map(|i| (0..m).map(|j| inv[(i, j)]).collect())
            .collect();
        out.iter().flatten().all(|v| v.is_finite()).then_some(out)
    }

    /// Correlation in the public order: alpha, beta, exponents, threshold.
    fn correlation(&self) -> Option<Vec<Vec<f64>>> {
        let cov = self.cov.as_ref()?;
        let loc = self.data.loc;
        let mut order = vec![0, loc];
        order.extend(1..loc);
        if self.gamma.is_some() {
            order.push(loc + 1);
        }
        Some(
            order
                .iter()
                .map(|&i| {
                    order
                        .iter()
                        .map(|&j| cov[i][j] / (cov[i][i] * cov[j][j]).sqrt())
                        .collect()
                })
                .collect(),
        )
    }

    fn var(&self, grad: &[f64]) -> Option<f64> {
        let cov = self.cov.as_ref()?;
        let mut v = 0.0;
        for i in 0..grad.len() {
            for j in 0..grad.len() {
                v += grad[i] * cov[i][j] * grad[j];
            }
        }
        (v >= 0.0).then_some(v)
    }

    /// ℓ of the fields in V/m: the normalised ℓ minus Σδ ln E_ref (the density
    /// of E is that of E/E_ref over E_ref).
    fn loglik_si(&self) -> f64 {
        let l = match self.gamma {
            Some(g) => threshold::loglik(self, g, &self.point),
            None => self.data.loglik(&self.point, 0.0),
        };
        l - self.data.r * self.scale.ln()
    }

    /// α (or a percentile, by its offset K) on the log scale: value, σ, Fisher
    /// bounds exp(ln E ± z σ_lnE), LR bounds by the profile of u with offset K.
    fn estimate_log(&self, hold: Hold, k: f64) -> Estimate {
        let loc = self.data.loc;
        let q = self.point.c[0] + k / self.point.beta;
        let mut grad = vec![0.0; self.dim()];
        grad[0] = 1.0;
        grad[loc] = -k / (self.point.beta * self.point.beta);
        let se = self.var(&grad).map(f64::sqrt);
        let value = self.scale * q.exp();
        Estimate {
            value,
            std_error: se.map(|s| s * value),
            fisher95: se.map(|s| (value * (-Z_975 * s).exp(), value * (Z_975 * s).exp())),
            lr95: self
                .lr_interval(hold, k, q, se)
                .map(|(a, b)| (self.scale * a.exp(), self.scale * b.exp())),
        }
    }

    /// β: Fisher bounds β·exp(±z σ_β/β), LR bounds by the profile of β (searched in ln β).
    fn estimate_beta(&self) -> Estimate {
        let loc = self.data.loc;
        let b = self.point.beta;
        let se = self.cov.as_ref().map(|c| c[loc][loc].sqrt());
        Estimate {
            value: b,
            std_error: se,
            fisher95: se.map(|s| (b * (-Z_975 * s / b).exp(), b * (Z_975 * s / b).exp())),
            lr95: self
                .lr_interval(Hold::Beta, 0.0, b.ln(), se.map(|s| s / b))
                .map(|(lo, hi)| (lo.exp(), hi.exp())),
        }
    }

    /// A covariate exponent: symmetric Fisher bounds, LR bounds by its profile.
    fn estimate_linear(&self, hold: Hold) -> Estimate {
        let Hold::Loc(j) = hold else {
            unreachable!("exponents are location coefficients")
        };
        let v = self.point.c[j];
        let se = self.cov.as_ref().map(|c| c[j][j].sqrt());
        Estimate {
            value: v,
            std_error: se,
            fisher95: se.map(|s| (v - Z_975 * s, v + Z_975 * s)),
            lr95: self.lr_interval(hold, 0.0, v, se),
        }
    }

    /// Likelihood-ratio 95 % interval of the held coordinate (u with offset k, an
    /// exponent, or ln β): the two values where the profile ℓ_p(v) = ℓ̂ − χ²₁(0.95)/2.
    /// Each side: step out from v̂ by Fisher's 1.96σ (doubling) until ℓ_p falls below
    /// the level, then Newton on ℓ_p(v) − level with dℓ_p/dv = ∂ℓ/∂v at the inner
    /// maximum (envelope theorem), kept inside the bracket by bisection. None for
    /// fits without a likelihood maximum, or when a side never falls below the
    /// level (an unbounded interval).
    fn lr_interval(&self, hold: Hold, k: f64, center: f64, se: Option<f64>) -> Option<(f64, f64)> {
        let top = self.lr_max?;
        let level = top - CHI2_1_95 / 2.0;
        let step0 = se
            .filter(|s| *s > 0.0)
            .map_or(0.1 + 0.1 * center.abs(), |s| Z_975 * s);
        let side = |sign: f64| -> Option<f64> {
            let mut warm = self.point;
            let profile = |v: f64, warm: &mut Point| -> Option<(f64, f64)> {
                let mut p = *warm;
                match hold {
                    Hold::Beta => p.beta = v.exp(),
                    Hold::Loc(j) => p.c[j] = v,
                    Hold::Nothing => return None,
                }
                let m = self.data.maximize(p, hold, k).ok()?;
                *warm = m.point;
                let slope = m.held_slope;
                let slope = if hold == Hold::Beta {
                    slope * m.point.beta
                } else {
                    slope
                };
                Some((m.loglik - level, slope))
            };
            let mut inner = center;
            let mut step = step0;
            let mut outer = center + sign * step;
            let mut h_out = profile(outer, &mut warm)?;
            let mut tries = 0;
            while h_out.0 > 0.0 {
                tries += 1;
                if tries > 40 {
                    return None;
                }
                inner = outer;
                step *= 2.0;
                outer = center + sign * step;
                h_out = profile(outer, &mut warm)?;
            }
            // Bracket [inner (h > 0), outer (h ≤ 0)]; Newton from the outer end.
            let (mut v, mut h) = (outer, h_out);
            for _ in 0..100 {
                // ℓ to 1e-9 (v to ≈ 10⁻⁹σ, as dℓ_p/dv ≈ 2/σ at the bound), or a
                // bracket narrower than 10⁻¹⁰ of the first step.
                if h.0.abs() < 1e-9 || (outer - inner).abs() < 1e-10 * step0 {
                    return Some(v);
                }
                let newton = v - h.0 / h.1;
                let next = if newton.is_finite() && (newton - inner) * (newton - outer) < 0.0 {
                    newton
                } else {
                    0.5 * (inner + outer)
                };
                v = next;
                h = profile(v, &mut warm)?;
                if h.0 > 0.0 {
                    inner = v;
                } else {
                    outer = v;
                }
            }
            Some(v)
        };
        let lo = side(-1.0)?;
        let hi = side(1.0)?;
        Some((lo, hi))
    }
}

impl WeibullFit {
    /// The percentile E_p = α·(−ln(1 − p))^(1/β) (+ γ with a threshold) at the
    /// reference covariates, at the electrode area `area` (None: the reference
    /// area). At another area A, p maps to p' = 1 − (1 − p)^(A/A₀) at A₀ (weakest
    /// link), the same as α_A = α·(A₀/A)^(1/β); so ln E_p = ln α + K/β with
    /// K = ln(−ln(1 − p)) + ln(A₀/A). σ by the delta method on ln E_p; LR bounds by
    /// the profile likelihood of ln E_p (module likelihood: u with offset K).
    pub fn percentile(&self, p: f64, area: Option<f64>) -> Result<Percentile, WeibullError> {
        if !(p > 0.0 && p < 1.0) {
            return Err(WeibullError::Unsupported(format!(
                "percentile {p} is not a probability strictly between 0 and 1"
            )));
        }
        let ln_area = match (area, self.reference_area) {
            (None, _) => 0.0,
            (Some(a), Some(a0)) if a.is_finite() && a > 0.0 => (a0 / a).ln(),
            (Some(a), Some(_)) => {
                return Err(WeibullError::Unsupported(format!(
                    "area {a} m² is not a positive number"
                )))
            }
            (Some(_), None) => return Err(WeibullError::Unsupported(
                "the series has no electrode area: give the specimens' area to scale to another"
                    .into(),
            )),
        };
        let k = (-(-p).ln_1p()).ln() + ln_area;
        let estimate = match self.model.gamma {
            Some(g) => threshold::percentile(&self.model, g, k),
            None => self.model.estimate_log(Hold::Loc(0), k),
        };
        Ok(Percentile {
            p,
            area: area.or(self.reference_area),
            estimate,
        })
    }

    /// α at another electrode area (weakest link): α_A = α·(A₀/A)^(1/β), with σ and
    /// bounds: the percentile p = 1 − e⁻¹ ≈ 63.2 % at that area.
    pub fn alpha_at(&self, area: f64) -> Result<Percentile, WeibullError> {
        self.percentile(-(-1f64).exp_m1(), Some(area))
    }

    /// Fisher 95 % confidence band of F(E) at the reference area and covariates:
    /// y = ln(−ln(1 − F)) = β(ln(E − γ) − ln α), σ_y by the delta method, the band
    /// F = 1 − exp(−exp(y ± z σ_y)) (Meeker & Escobar 1998 §8.4.3). (F, F) where σ
    /// is unknown; (0, 0) below a threshold.
    pub fn band(&self, fields: &[f64]) -> Vec<(f64, f64)> {
        let m = &self.model;
        let loc = m.data.loc;
        let b = m.point.beta;
        fields
            .iter()
            .map(|&e| {
                let shifted = e - m.gamma.unwrap_or(0.0);
                if shifted <= 0.0 {
                    return (0.0, 0.0);
                }
                let x = (shifted / m.scale).ln() - m.point.c[0];
                let y = b * x;
                let mut grad = vec![0.0; m.dim()];
                grad[0] = -b;
                grad[loc] = x;
                if m.gamma.is_some() {
                    grad[loc + 1] = -b / shifted;
                }
                let s = m.var(&grad).map_or(0.0, f64::sqrt);
                let f = |y: f64| -(-y.exp()).exp_m1();
                (f(y - Z_975 * s), f(y + Z_975 * s))
            })
            .collect()
    }

    /// The fitted two-parameter law at the reference area and covariates (the
    /// shared core's [`Weibull`]: its cdf, percentile and area scaling).
    pub fn law(&self) -> Weibull {
        Weibull {
            alpha: self.alpha.value,
            beta: self.beta.value,
        }
    }

    /// The fitted CDF F(E) at the reference area and covariates (E − γ with a
    /// threshold).
    pub fn cdf(&self, field: f64) -> f64 {
        self.law().cdf(field - self.model.gamma.unwrap_or(0.0))
    }
}
