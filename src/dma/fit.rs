//! `dea-fit dma`: isotherms → free shifts (→ shift law) → master curve (→ Prony).

use super::law::{self, LawFit, LawKind};
use super::shift::{self, PairShift, ShiftOn};
use super::temperature::celsius;
use super::{DmaData, DmaSource};
use crate::error::{Error, Result};
use crate::fit::prony::frequency::{self, ComplexModulus, FrequencyFit, FrequencySettings};
use crate::fit::prony::{Search, ShiftCovariance};
use crate::fit::Status;
use serde::{Deserialize, Serialize};

/// Schema tag of a DMA run's file: shifts, shift law, master curve and its Prony
/// series. It is a relaxation-kind material file: scenes and `export` read it
/// ([`crate::material::file::DMA_SCHEMA`]).
pub const SCHEMA: &str = crate::material::file::DMA_SCHEMA;

/// Which shifts build the master curve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShiftMode {
    /// The free shifts.
    Free,
    /// A law fitted to the free shifts.
    Law(LawKind),
}

/// What `dma` does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// The quantity the shifts are computed on.
    pub on: ShiftOn,
    /// Fit a vertical shift too.
    pub vertical: bool,
    /// Free shifts or a law.
    pub mode: ShiftMode,
    /// Reference temperature (K): required for isotherms, optional for a master curve.
    pub reference_k: Option<f64>,
    /// Prony terms (None: auto), for the Prony step.
    pub terms: Option<usize>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            on: ShiftOn::Storage,
            vertical: false,
            mode: ShiftMode::Free,
            reference_k: None,
            terms: None,
        }
    }
}

/// One isotherm's shift relative to the reference temperature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShiftFactor {
    /// The isotherm's temperature (K).
    #[serde(rename = "temperature_K")]
    pub temperature_k: f64,
    /// Free log10 aT (reduced frequency = aT·ω).
    #[serde(rename = "log10_aT")]
    pub log10_at: f64,
    /// Its standard error (decades).
    pub std_error: f64,
    /// The law's log10 aT, when a law was fitted.
    #[serde(
        rename = "law_log10_aT",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub law_log10_at: Option<f64>,
    /// Free − law (offset by their mean), decades.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub law_residual_decades: Option<f64>,
    /// log10 bT (modulus divided by bT on the master curve), with a vertical shift.
    #[serde(rename = "log10_bT", default, skip_serializing_if = "Option::is_none")]
    pub log10_bt: Option<f64>,
    /// Its standard error.
    #[serde(
        rename = "log10_bT_std_error",
        default,
        skip_serializing_if = "Option::is_none"
    )]
    pub log10_bt_std_error: Option<f64>,
}

/// One point of the master curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MasterPoint {
    /// Reduced angular frequency aT·ω (rad/s).
    pub reduced_omega_rad_s: f64,
    /// E′/bT (Pa).
    #[serde(rename = "storage_Pa")]
    pub storage_pa: f64,
    /// E″/bT (Pa).
    #[serde(rename = "loss_Pa")]
    pub loss_pa: f64,
    /// The isotherm's temperature (K); None on a master curve read as such.
    #[serde(rename = "temperature_K")]
    pub temperature_k: Option<f64>,
}

/// The Prony series of the master curve (Pa, s): E(t) = E∞ + Σ Eᵢ e^(−t/τᵢ),
/// fitted to E′ and E″ against reduced ω together ([`crate::fit::prony::frequency`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PronyOut {
    /// E∞ (Pa).
    #[serde(rename = "E_inf")]
    pub e_inf: f64,
    /// The terms, by τ.
    pub terms: Vec<PronyTermOut>,
    /// The whole frequency-domain fit: σ of every term, identifiability, the τ
    /// range the master curve supports, the Kramers–Kronig check, the term choice.
    pub fit: FrequencyFit,
}

/// One term.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PronyTermOut {
    /// Eᵢ (Pa).
    #[serde(rename = "E")]
    pub e: f64,
    /// τᵢ (s).
    pub tau: f64,
}

/// The result of `dea-fit dma`, the fit file's object.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DmaFit {
    /// Schema tag ([`SCHEMA`]).
    pub schema: String,
    /// Outcome.
    pub status: Status,
    /// Reference temperature (K); None for a master curve given without one.
    #[serde(rename = "reference_temperature_K")]
    pub reference_temperature_k: Option<f64>,
    /// `free`, `wlf` or `arrhenius`: the shifts the master curve was built with.
    pub shift: String,
    /// What the shifts were computed on.
    pub shift_on: ShiftOn,
    /// Whether a vertical shift was fitted.
    pub vertical_shift: bool,
    /// Each isotherm's shift, coldest first.
    pub shift_factors: Vec<ShiftFactor>,
    /// The shifts of adjacent pairs, each with its overlap.
    pub pair_shifts: Vec<PairShift>,
    /// The law fitted to the free shifts (`--shift wlf|arrhenius`).
    pub shift_model: Option<LawFit>,
    /// The master curve at the reference temperature, by reduced frequency.
    pub master_curve: Vec<MasterPoint>,
    /// Its reduced angular frequencies, lowest and highest (rad/s).
    pub reduced_omega_range_rad_s: [f64; 2],
    /// The Prony series fitted to the master curve ([`prony_step`]).
    pub prony: PronyOut,
    /// What to read before using the result.
    pub warnings: Vec<String>,
    /// The files read.
    pub files: Vec<DmaSource>,
}

/// Shift `data`, build its master curve and fit its Prony series.
pub fn fit(data: &DmaData, settings: &Settings) -> Result<DmaFit> {
    let mut warnings: Vec<String> = data
        .sources
        .iter()
        .flat_map(|s| s.notes.iter().map(move |n| format!("{}: {n}", s.path)))
        .collect();
    let notes = warnings.len();
    if settings.vertical && settings.on == ShiftOn::TanDelta {
        return Err(Error::settings(
            "--vertical-shift cannot be found from tan δ, which a vertical shift leaves unchanged",
        )
        .with_hint("shift on storage, loss or both with --vertical-shift"));
    }
    let (factors, pairs, model, master, shifts) = if data.is_master() {
        if settings.mode != ShiftMode::Free {
            return Err(Error::settings(
                "--shift wlf|arrhenius needs isotherms; this is a master curve (no temperature)",
            )
            .with_hint("give the isotherms with their temperatures, or leave out --shift"));
        }
        let iso = &data.isotherms[0];
        let master = (0..iso.len())
            .map(|i| MasterPoint {
                reduced_omega_rad_s: iso.omega[i],
                storage_pa: iso.storage[i],
                loss_pa: iso.loss[i],
                temperature_k: None,
            })
            .collect();
        (Vec::new(), Vec::new(), None, master, None)
    } else {
        shifted(data, settings, &mut warnings)?
    };
    let lo = master
        .iter()
        .map(|p: &MasterPoint| p.reduced_omega_rad_s)
        .fold(f64::INFINITY, f64::min);
    let hi = master
        .iter()
        .map(|p| p.reduced_omega_rad_s)
        .fold(0.0, f64::max);
    let (prony, prony_status) = prony_step(&master, shifts.as_ref(), settings, &mut warnings)?;
    // what the reader did is said, and does not make the result a warning; a
    // blocking status of the Prony fit is the run's
    let status = match prony_status {
        Status::Ok | Status::Warning if warnings.len() == notes => Status::Ok,
        Status::Ok | Status::Warning => Status::Warning,
        blocking => blocking,
    };
    Ok(DmaFit {
        schema: SCHEMA.into(),
        status,
        reference_temperature_k: settings.reference_k,
        shift: match settings.mode {
            ShiftMode::Free => "free".into(),
            ShiftMode::Law(LawKind::Wlf) => "wlf".into(),
            ShiftMode::Law(LawKind::Arrhenius) => "arrhenius".into(),
        },
        shift_on: settings.on,
        vertical_shift: settings.vertical,
        shift_factors: factors,
        pair_shifts: pairs,
        shift_model: model,
        master_curve: master,
        reduced_omega_range_rad_s: [lo, hi],
        prony,
        warnings,
        files: data.sources.clone(),
    })
}

/// The Prony step: the frequency-domain Prony fit of the master curve (E′ and E″
/// against reduced ω, `settings.terms` terms or auto; the Prony core shared with
/// `relaxation`, [`crate::fit::prony::frequency::fit`]), the uncertainty of the
/// shifts that built it (`shifts`, by master point) carried into its σ. Its
/// warnings join the run's, prefixed; its status is returned for the run's.
fn prony_step(
    master: &[MasterPoint],
    shifts: Option<&ShiftCovariance>,
    settings: &Settings,
    warnings: &mut Vec<String>,
) -> Result<(PronyOut, Status)> {
    let omega: Vec<f64> = master.iter().map(|p| p.reduced_omega_rad_s).collect();
    let storage: Vec<f64> = master.iter().map(|p| p.storage_pa).collect();
    let loss: Vec<f64> = master.iter().map(|p| p.loss_pa).collect();
    let data = ComplexModulus {
        omega_rad_s: &omega,
        storage_pa: &storage,
        loss_pa: &loss,
        shifts,
    };
    // auto tries up to one term per decade of the master curve (Park & Schapery
    // 1999 place one τ a decade), at least the core's default 6: on the shipped
    // 12-decade curve 6 terms left E′ 2.5 % rms off (noise 1 %) and the
    // Kramers–Kronig check, fitting E′ alone with as few, flagged four ranges of a
    // consistent synthetic curve
    let decades = match (
        omega.iter().copied().reduce(f64::min),
        omega.iter().copied().reduce(f64::max),
    ) {
        (Some(lo), Some(hi)) if lo > 0.0 && hi > lo => (hi / lo).log10().ceil() as usize,
        _ => 0,
    };
    let default = Search::default();
    let fs = FrequencySettings {
        search: Search {
            terms: settings.terms,
            max_terms: decades.clamp(default.max_terms, frequency::MAX_TERMS),
            ..default
        },
        ..FrequencySettings::default()
    };
    let f = frequency::fit(&data, &fs)?;
    warnings.extend(f.warnings.iter().map(|w| format!("Prony series: {w}")));
    let out = PronyOut {
        e_inf: f.e_inf_pa,
        terms: f
            .terms
            .iter()
            .map(|t| PronyTermOut {
                e: t.modulus_pa,
                tau: t.tau_s,
            })
            .collect(),
        fit: f.clone(),
    };
    Ok((out, f.status))
}

type Shifted = (
    Vec<ShiftFactor>,
    Vec<PairShift>,
    Option<LawFit>,
    Vec<MasterPoint>,
    Option<ShiftCovariance>,
);

/// Free shifts of adjacent isotherms, accumulated to Tr, the law, the master curve.
fn shifted(data: &DmaData, settings: &Settings, warnings: &mut Vec<String>) -> Result<Shifted> {
    let iso = &data.isotherms;
    let tr = settings.reference_k.ok_or_else(|| {
        Error::settings("isotherms need a reference temperature for their master curve")
            .with_hint("e.g. --reference-temperature 25C (it need not be one of the isotherms)")
    })?;
    if iso.len() < 2 {
        return Err(Error::settings(format!(
            "one isotherm ({}) gives no shift: a master curve needs at least two temperatures",
            celsius(iso[0].temperature_k.unwrap_or(f64::NAN))
        ))
        .with_hint("give the other isotherms too, or a master curve without temperature"));
    }
    let temps: Vec<f64> = iso
        .iter()
        .map(|i| i.temperature_k.expect("isotherms have temperatures"))
        .collect();
    let pairs = iso
        .windows(2)
        .map(|w| shift::pair(&w[0], &w[1], settings.on, settings.vertical))
        .collect::<Result<Vec<PairShift>>>()?;
    for p in &pairs {
        if let Some(w) = monotonic_warning(p, settings.on) {
            warnings.push(w);
        } else if p.at_edge {
            warnings.push(format!(
                "the shift between {} and {} rests on the fewest points allowed ({} in the overlap): the isotherms barely overlap",
                celsius(p.cold_k),
                celsius(p.warm_k),
                p.overlap_points
            ));
        }
    }
    let rho = shift::adjacent_correlations(iso, &pairs, settings.on);
    let acc = shift::accumulate(&temps, &pairs, &rho, tr);
    let model = match settings.mode {
        ShiftMode::Free => {
            if acc.extrapolated {
                warnings.push(format!(
                    "the reference temperature {} lies outside the isotherms ({} … {}): the free shifts are referred to it by extrapolating the nearest two; a law (--shift wlf) extrapolates better",
                    celsius(tr),
                    celsius(temps[0]),
                    celsius(temps[temps.len() - 1])
                ));
            }
            None
        }
        ShiftMode::Law(kind) => {
            let f = law::fit(kind, &temps, &pairs, &acc.log_at, tr).ok_or_else(|| {
                Error::settings(format!(
                    "{} needs at least three isotherms (two pair shifts) for its two constants",
                    kind.label()
                ))
            })?;
            law_warnings(&f, &temps, warnings);
            Some(f)
        }
    };
    let factors: Vec<ShiftFactor> = temps
        .iter()
        .enumerate()
        .map(|(j, &t)| ShiftFactor {
            temperature_k: t,
            log10_at: acc.log_at[j],
            std_error: acc.std_error[j],
            law_log10_at: model.as_ref().map(|m| m.law.log_at(t)),
            law_residual_decades: model.as_ref().map(|m| m.residual_decades[j]),
            log10_bt: acc.log_bt.as_ref().map(|b| b[j]),
            log10_bt_std_error: acc.bt_std_error.as_ref().map(|b| b[j]),
        })
        .collect();
    let mut master = Vec::new();
    for (j, i) in iso.iter().enumerate() {
        let f = &factors[j];
        let a = 10f64.powf(f.law_log10_at.unwrap_or(f.log10_at));
        let b = 10f64.powf(f.log10_bt.unwrap_or(0.0));
        for k in 0..i.len() {
            master.push((
                j,
                MasterPoint {
                    reduced_omega_rad_s: a * i.omega[k],
                    storage_pa: i.storage[k] / b,
                    loss_pa: i.loss[k] / b,
                    temperature_k: Some(f.temperature_k),
                },
            ));
        }
    }
    master.sort_by(|a, b| a.1.reduced_omega_rad_s.total_cmp(&b.1.reduced_omega_rad_s));
    let (group, master): (Vec<usize>, Vec<MasterPoint>) = master.into_iter().unzip();
    // the shifts the master curve was built with, and their covariance
    let horizontal = match &model {
        None => Some(acc.covariance.clone()),
        Some(m) => m.shift_covariance(&temps, &pairs, &rho.0),
    };
    let shifts = match horizontal {
        Some(horizontal) => Some(ShiftCovariance {
            group,
            horizontal,
            vertical: acc.bt_covariance.clone(),
        }),
        None => {
            warnings.push(format!(
                "the {} constants have no standard error, so the shifts' uncertainty is not in the Prony series' σ (they are too narrow)",
                model.as_ref().map_or("shift law", |m| m.law.kind.label())
            ));
            None
        }
    };
    Ok((factors, pairs, model, master, shifts))
}

/// The warning for a pair whose shift is not positive (the colder isotherm should
/// sit at higher reduced frequency), saying why it may be so.
pub fn monotonic_warning(p: &PairShift, on: ShiftOn) -> Option<String> {
    if p.log_shift > 0.0 {
        return None;
    }
    let flat = p.overlap_span_decades < (3.0 * p.rms_mismatch).max(0.05);
    let why = if p.at_edge {
        format!(
            "the overlap holds only {} points: the isotherms barely overlap",
            p.overlap_points
        )
    } else if flat {
        format!(
            "the shifted quantity ({}) changes by {:.3} decades across the overlap: the curves are flat there and give nothing to shift on (shift on another quantity, --shift-on)",
            on.name(),
            p.overlap_span_decades
        )
    } else if p.log_shift.abs() < 2.0 * p.std_error {
        "it is zero within 2σ: the two isotherms coincide".to_string()
    } else {
        "the isotherms cross: the material is not thermorheologically simple between these temperatures (a transition?)".to_string()
    };
    Some(format!(
        "shifts are not monotonic in temperature: the isotherm at {} moves {:+.3} ± {:.3} decades against the one at {} (a colder isotherm belongs at higher reduced frequency): {why}",
        celsius(p.cold_k),
        p.log_shift,
        p.std_error,
        celsius(p.warm_k)
    ))
}

/// The warnings of a fitted law: it misses the free shifts by more than their own
/// uncertainty (χ² above its 99 % point) or by more than [`law::RMS_WARNING_DECADES`]
/// rms; C2 not determined.
fn law_warnings(f: &LawFit, temps: &[f64], warnings: &mut Vec<String>) {
    let name = f.law.kind.label();
    let worst = f
        .residual_decades
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .map(|(j, r)| format!("{r:+.2} decades at {}", celsius(temps[j])))
        .unwrap_or_default();
    if f.rms_decades > law::RMS_WARNING_DECADES {
        warnings.push(format!(
            "{name} fits the free shifts poorly: {:.2} decades rms (max {worst}), more than {} decades; the master curve built with it is off by as much (use --shift free, or the other law)",
            f.rms_decades,
            law::RMS_WARNING_DECADES
        ));
    } else if f.chi2 > f.chi2_99 {
        warnings.push(format!(
            "{name} misses the free shifts by more than their own uncertainty: χ² = {:.1} for {} degrees of freedom (99 % point {:.1}); rms {:.3} decades, max {worst}",
            f.chi2, f.dof, f.chi2_99, f.rms_decades
        ));
    }
    if f.c2_at_bound {
        warnings.push(
            "WLF C2 ran to its bound: the shifts are straight in T over these isotherms and do not determine C2 (Arrhenius, --shift arrhenius, needs one constant)".to_string(),
        );
    }
}
