//! Model no more than the trace needs, by default: when the scene's full model
//! leaves constants not identifiable ([`crate::fit::identifiability`], the one
//! rule), the answer is the smallest model whose constants all are, found by
//! backward elimination; and the constants every identification holds (fixed by
//! the user, held at the scene's values, dropped by the reduction), typed, for
//! every output.
//!
//! **Backward elimination** ([`identify`]). After the full model's fit, while some
//! constant is not identifiable, one is dropped per round, in this priority
//! (of the constants not identifiable):
//! 1. εr (or the filler mass fraction that sets it): it cannot be dropped (the
//!    Maxwell pressure needs it), so it is held at the scene's stated value, and
//!    every other interval is then conditional on that value (the output says so:
//!    [`Held`], `conditional_on`). It goes first because a weak εr (a trace
//!    without capacitance sees only εr over the moduli) lets every modulus drift
//!    with it: dropping terms first would chase that drift (on a contraction-only
//!    trace of a one-arm Yeoh stack, C10 went to 6.9 MPa with εr = 457, and four
//!    rounds dropped C30, C20, the arm and nv to a model 880 AICc worse);
//! 2. the highest higher-order hyperelastic term, set to 0: Yeoh C30, then C20;
//!    Mooney-Rivlin C01 (leaving neo-Hookean); an Ogden pair beyond the first
//!    (μk = 0, its αk then acts on nothing and is held where it was); Gent's Jm,
//!    set to its largest value [`JM_MAX`] (the neo-Hookean limit, to (I1 − 3)/2Jm
//!    relative);
//!
//! Not dropped: a Maxwell arm or the dashpot nv that the trace does not pin down.
//! Removing them was tried and measured (tests/identify_coverage.rs): an arm as
//! slow as the trace, removed, left its stiffness to C10 and the fast arm, whose
//! intervals then held the truth 0 of 17 times; an arm the trace partly sees
//! (τ = 0.3 s at 0.3 % strain) was removed in 7 of 20 replicates, and C10's and
//! arm 1's intervals missed in exactly those. The dynamic part of the model is
//! what the trace measures, so a weak arm stays free and not identifiable (the
//! run `ill_posed`), and every other interval accounts for it (the covariance
//! with it free, or its profile). `--fix nv=0` or a scene without the arm remain
//! the user's choice, stated.
//!
//! A constant that ended at a bound of its search box because the trace pushed it
//! there (not one that drifted there along a direction the trace does not pin
//! down) is not dropped: the box is wrong, not the model; the run stays
//! `ill_posed` and its reason says to start the scene nearer.
//! A constant of none of these kinds (the leading modulus traded against another)
//! is left as it is: the reduction stops when nothing it may drop is
//! not identifiable, and the status then says `ill_posed`. Each round refits from
//! [`REFIT_STARTS`] starts, the previous optimum and the scene's values, with the
//! full model's noise σ (so that χ² and AICc compare across the rounds), and
//! re-assesses. A model the reduction shrinks further is judged by its linear
//! (Wald) assessment alone ([`super::Settings::reducing`]): the profile checks of
//! its intervals (most of a round's cost: on the rig trace 4.2 s of CPU time for the
//! whole run with them, 2.5 s without) would serve no output; the model reported
//! gets them, and when they find a constant the linear assessment did not, the
//! reduction goes on from there.
//!
//! Beside the reduced model stand the full model's χ²/dof and AICc and
//! ΔAICc = AICc(reduced) − AICc(full) (both on the same σ): above
//! [`MAX_DELTA_AICC`] the full model is much better (Burnham & Anderson 2002:
//! ΔAICc > 10, essentially no support for the worse model), so the dropped terms
//! together matter even though none is identifiable on its own, and the run is a
//! `warning` at least. `--free`, `--fix`, `--hyperelastic auto` and `--arms auto`
//! say what to fit, and then nothing is reduced.

use super::assessment::Estimate;
use super::noise::Sigma;
use super::params::{self, Constant, Role};
use super::problem::Experiment;
use super::{identify_with, Identification, Run, Settings};
use crate::error::Result;
use crate::fit::lm::Control;
use crate::fit::Status;
use crate::material::hyperelastic::gent::JM_MAX;
use crate::report::format::si;
use serde::Serialize;
use std::time::Instant;

/// ΔAICc = AICc(reduced) − AICc(full) above which the dropped terms together
/// matter: the run warns (Burnham & Anderson 2002, §2.6: ΔAICc > 10 leaves the
/// worse model essentially no support).
pub const MAX_DELTA_AICC: f64 = 10.0;

/// What the assessment's reason of a constant at a bound says when it drifted
/// there ([`super::assessment`]): the with-every-constant-free weakness follows.
const DRIFTED: &str = "it drifted there";

/// Starts of each refit of the reduction: the previous optimum and the scene's
/// values.
pub const REFIT_STARTS: usize = 2;

/// How a constant that is not fitted got its value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum How {
    /// Typed in: `--fix NAME=VALUE` (a stated value).
    Fixed,
    /// The scene's value: `--fix NAME`, not named in `--free`, or held there by
    /// the reduction (εr that a trace cannot pin down).
    Scene,
    /// Dropped by the reduction: a hyperelastic term set to 0 (Gent's Jm to its
    /// neo-Hookean limit [`JM_MAX`]).
    Dropped,
}

/// A constant held during the fit, and why.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Held {
    /// Name (`C20`, `arm2.k`, `eps_r`).
    pub name: String,
    /// Its value (SI); 0 for a dropped term ([`JM_MAX`] for Gent's Jm).
    pub value: f64,
    /// SI unit.
    pub unit: String,
    /// How it got the value.
    pub how: How,
    /// Why (for what the reduction held or dropped: the assessment's reason).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
}

/// The held constants the estimates' intervals are conditional on: every one but
/// those dropped (a term the model no longer has conditions nothing).
pub fn conditional_on(held: &[Held]) -> Vec<String> {
    held.iter()
        .filter(|h| h.how != How::Dropped)
        .map(|h| h.name.clone())
        .collect()
}

/// One round of the reduction.
#[derive(Debug, Clone, Serialize)]
pub struct Round {
    /// The constant it dropped (or held, for εr).
    pub constant: String,
    /// What it did, e.g. `C30 = 0`, `eps_r held at 4.7`.
    pub action: String,
    /// Why: the assessment's reason for that constant in the model before.
    pub reason: String,
    /// χ²/dof of the model after the round (the full model's σ).
    pub chi2_per_dof: f64,
    /// AICc of the model after the round.
    pub aicc: Option<f64>,
}

/// The full model's fit, beside the reduced one.
#[derive(Debug, Clone, Serialize)]
pub struct FullFit {
    /// Free constants.
    pub free: usize,
    /// χ²/(N − p).
    pub chi2_per_dof: f64,
    /// AICc.
    pub aicc: Option<f64>,
    /// Its status.
    pub status: Status,
    /// The constants it did not pin down.
    pub not_identifiable: Vec<String>,
}

/// What the reduction did.
#[derive(Debug, Clone, Serialize)]
pub struct Reduction {
    /// The full model's fit.
    pub full: FullFit,
    /// The rounds, in order.
    pub rounds: Vec<Round>,
    /// AICc(reduced) − AICc(full), same σ (None when either is undefined).
    pub delta_aicc: Option<f64>,
    /// The flags that give the reduced model directly (`--fix C20=0,C30=0`), when
    /// flags can.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flags: Option<String>,
    /// Wall-clock seconds of the full fit and every round.
    pub seconds: f64,
}

/// The held constants of a run: every constant of the scene that is not free, its
/// value from θ; `stated` the indices in θ that `--fix NAME=VALUE` set.
pub fn held(all: &[Constant], free: &[Constant], stated: &[usize], theta: &[f64]) -> Vec<Held> {
    all.iter()
        .filter(|c| !free.iter().any(|f| f.name == c.name))
        .map(|c| Held {
            name: c.name.clone(),
            value: theta[c.index],
            unit: c.unit.to_string(),
            how: match stated.contains(&c.index) {
                true => How::Fixed,
                false => How::Scene,
            },
            reason: None,
        })
        .collect()
}

/// The `--fix` list that drops the higher-order term `c` of `free` and every
/// higher one of the same model (`C20=0,C30=0`; an Ogden pair's μ at 0 with its α
/// held at the scene's value): the advice for a term the trace cannot see, which
/// is what the default run does to it; Gent's Jm at [`JM_MAX`] (`Jm=1e6`). None
/// for a term that nothing drops (the leading Ogden pair's α).
pub fn drop_advice(free: &[Constant], c: &Constant) -> Option<String> {
    let ogden = c.name.starts_with("alpha") || c.name.starts_with("mu");
    let from = match ogden {
        true => c.index / 2 * 2,
        false => c.index,
    };
    if c.role != Role::HigherOrder || (ogden && from == 0) {
        return None;
    }
    if c.name == JM {
        return Some(format!("{JM}={JM_MAX:e}"));
    }
    let list: Vec<String> = free
        .iter()
        .filter(|k| k.role == Role::HigherOrder && k.index >= from)
        .map(|k| match k.name.starts_with("alpha") {
            true => format!("{}={}", k.name, k.start),
            false => format!("{}=0", k.name),
        })
        .collect();
    Some(list.join(","))
}

/// Gent's limiting-chain parameter.
const JM: &str = "Jm";

/// What one round does.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Step {
    /// Fix these constants at these values (the first is the one dropped).
    Zero(Vec<(String, f64)>),
    /// Hold this constant at the scene's value.
    Hold(String),
}

/// The next step of the reduction for the estimates `estimates` of a model
/// `model` with the constants `all` (module documentation's priority): the step,
/// the constant it is about and the assessment's reason; None when nothing it may
/// drop is weak.
pub(super) fn next_step(
    estimates: &[Estimate],
    all: &[Constant],
    model: &str,
) -> Option<(Step, String, String)> {
    // a constant the trace pushed onto a bound of its box (not one that drifted
    // there along a direction the trace does not pin down) is well seen: the box is
    // wrong, not the model, and dropping it would lie
    let weak: Vec<&Constant> = all
        .iter()
        .filter(|c| {
            estimates.iter().any(|e| {
                e.name == c.name
                    && !e.identifiable
                    && (!e.at_bound || e.reason.as_deref().is_some_and(|r| r.contains(DRIFTED)))
            })
        })
        .collect();
    let reason = |name: &str| {
        estimates
            .iter()
            .find(|e| e.name == name)
            .and_then(|e| e.reason.clone())
            .unwrap_or_default()
    };
    let value = |name: &str| {
        estimates
            .iter()
            .find(|e| e.name == name)
            .map_or(0.0, |e| e.value)
    };
    // εr first: it cannot be dropped, and when it is weak (a trace without
    // capacitance sees only εr over the moduli) every modulus drifts with it, so
    // dropping terms first would chase that drift
    if let Some(c) = weak.iter().find(|c| c.role.is_dielectric()) {
        return Some((Step::Hold(c.name.clone()), c.name.clone(), reason(&c.name)));
    }
    let ogden = model.starts_with("ogden");
    let higher = weak
        .iter()
        .filter(|c| c.role == Role::HigherOrder && (!ogden || c.index >= 2))
        .max_by_key(|c| c.index);
    higher.map(|c| {
        let step = match ogden {
            true => {
                let pair = c.index / 2 + 1;
                let mu = format!("mu{pair}");
                let alpha = format!("alpha{pair}");
                let a = value(&alpha);
                Step::Zero(vec![(mu, 0.0), (alpha, a)])
            }
            false if c.name == JM => Step::Zero(vec![(c.name.clone(), JM_MAX)]),
            false => Step::Zero(vec![(c.name.clone(), 0.0)]),
        };
        (step, c.name.clone(), reason(&c.name))
    })
}

/// The values of `id`'s free constants by name: the warm start of the next round.
fn warm(id: &Identification) -> Vec<(String, f64)> {
    id.parameters
        .iter()
        .map(|e| (e.name.clone(), e.value))
        .collect()
}

/// `id` (identified with `settings`) identified again from its optimum, one
/// start, as a model reported: its intervals checked against profiles, its
/// integration error measured, the `profiles` asked for; `id` itself where that
/// fails (a warning says so when `id` is provisional: its checks are missing).
fn checked(
    experiments: &[Experiment],
    settings: &Settings,
    id: &Identification,
    profiles: Vec<String>,
    control: &(dyn Fn(usize) -> Control + Sync),
    warnings: &mut Vec<String>,
) -> Identification {
    let p = Settings {
        starts: 1,
        reducing: false,
        warm: warm(id),
        profiles,
        ..settings.clone()
    };
    let why = match identify_with(experiments.to_vec(), &p, control) {
        Ok(Run::Identified(again)) => return *again,
        Ok(Run::Failed(f)) => f.reason,
        Err(e) => e.to_string(),
    };
    if id.provisional {
        warnings.push(format!(
            "the intervals of the model reported were not checked against profiles, nor its integration error measured: its final identification failed ({why})"
        ));
    }
    id.clone()
}

/// Identify with the default model reduction (module documentation): the full
/// model first; when it leaves constants not identifiable, the rounds. Returns the
/// run (the reduced model's identification, with its [`Reduction`] and its held
/// constants, or the full model's when nothing was reduced). The rounds fix
/// constants of the same experiments, so `experiments` are also the ones
/// identified.
pub fn identify(
    experiments: &[Experiment],
    settings: &Settings,
    control: &(dyn Fn(usize) -> Control + Sync),
) -> Result<Run> {
    let t0 = Instant::now();
    let reducing = Settings {
        reducing: true,
        ..settings.clone()
    };
    let full = match identify_with(experiments.to_vec(), &reducing, control)? {
        Run::Identified(id) => *id,
        failed => return Ok(failed),
    };
    let weak = |id: &Identification| id.parameters.iter().any(|e| !e.identifiable);
    if !weak(&full) || full.status == Status::NotConverged {
        return Ok(Run::Identified(Box::new(full)));
    }
    // the rounds: the full model's σ, few starts, no checkpoints (those are the
    // full search's), profiles only at the end
    let mut s = reducing.clone();
    s.starts = REFIT_STARTS.min(settings.starts);
    s.profiles.clear();
    for e in &full.experiments {
        for c in &e.channels {
            if !s.sigma.iter().any(|(k, _)| *k == c.channel) {
                s.sigma.push((c.channel, Sigma::Absolute(c.sigma)));
            }
        }
    }
    let round_control = |i: usize| Control {
        checkpoint: None,
        resume: false,
        ..control(i)
    };
    let mut current = full.clone();
    let mut rounds = Vec::new();
    let mut dropped: Vec<Held> = Vec::new();
    let mut warnings = Vec::new();
    // a refit that did not converge reports nothing identifiable (its estimates
    // are not an optimum, [`super::Identification`]): the reduction stops there
    while weak(&current) && current.status != Status::NotConverged {
        let all = params::constants(&experiments[0].scene);
        let model = experiments[0].scene.material.spec.name.clone();
        let Some((step, name, reason)) = next_step(&current.parameters, &all, &model) else {
            break;
        };
        let mut next_settings = s.clone();
        let unit_of = |n: &str| {
            all.iter()
                .find(|c| c.name == n)
                .map_or("", |c| c.unit)
                .to_string()
        };
        let unit = unit_of(&name);
        let (action, held) = match &step {
            Step::Zero(list) => {
                for (n, v) in list {
                    next_settings.fix.push(format!("{n}={v:e}"));
                }
                let action = list
                    .iter()
                    .map(|(n, v)| format!("{n} = {}", si(*v, &unit_of(n))))
                    .collect::<Vec<_>>()
                    .join(", ");
                (action, How::Dropped)
            }
            Step::Hold(n) => {
                next_settings.fix.push(n.clone());
                let v = all
                    .iter()
                    .find(|c| c.name == *n)
                    .map_or(f64::NAN, |c| c.start);
                (
                    format!("{n} held at the scene's {}", si(v, &unit)),
                    How::Scene,
                )
            }
        };
        next_settings.warm = warm(&current);
        let label = format!("reduction round {}: {action}", rounds.len() + 1);
        let run = identify_with(experiments.to_vec(), &next_settings, &|i| Control {
            label: Some(label.clone()),
            ..round_control(i)
        });
        let id = match run {
            Ok(Run::Identified(id)) => *id,
            Ok(Run::Failed(f)) => {
                warnings.push(format!(
                    "the reduction stopped before {action}: its refit failed ({})",
                    f.reason
                ));
                break;
            }
            Err(e) => {
                warnings.push(format!(
                    "the reduction stopped before {action}: its refit was refused ({e})"
                ));
                break;
            }
        };
        match &step {
            Step::Zero(list) => dropped.extend(list.iter().map(|(n, v)| Held {
                name: n.clone(),
                value: *v,
                unit: unit_of(n),
                how: held,
                reason: Some(reason.clone()),
            })),
            Step::Hold(n) => dropped.push(Held {
                name: n.clone(),
                value: all
                    .iter()
                    .find(|c| c.name == *n)
                    .map_or(f64::NAN, |c| c.start),
                unit: unit.clone(),
                how: held,
                reason: Some(reason.clone()),
            }),
        }
        rounds.push(Round {
            constant: name,
            action,
            reason,
            chi2_per_dof: id.chi2_per_dof,
            aicc: id.aicc,
        });
        s = next_settings;
        current = id;
    }
    // A reduction that stopped early (a refit failed) reports a provisional model:
    // it is identified again from its optimum with what it skipped, the checks of
    // its intervals and of the integration error (and the profiles asked for).
    if rounds.is_empty() {
        let mut full = match full.provisional {
            true => checked(
                experiments,
                &reducing,
                &full,
                settings.profiles.clone(),
                &round_control,
                &mut warnings,
            ),
            false => full,
        };
        full.warnings.extend(warnings);
        return Ok(Run::Identified(Box::new(full)));
    }
    // profiles asked for: of the reduced model's constants, from its optimum
    let profiles: Vec<String> = settings
        .profiles
        .iter()
        .filter(|n| current.parameters.iter().any(|e| e.name == **n))
        .cloned()
        .collect();
    for n in settings.profiles.iter().filter(|n| !profiles.contains(n)) {
        warnings.push(format!(
            "no profile of {n}: the reduction dropped or held it"
        ));
    }
    if current.provisional || !profiles.is_empty() {
        current = checked(
            experiments,
            &s,
            &current,
            profiles,
            &round_control,
            &mut warnings,
        );
    }
    let mut id = current;
    // σ came from the full model's residuals, not from the user
    for (e, f) in id.experiments.iter_mut().zip(&full.experiments) {
        for (c, fc) in e.channels.iter_mut().zip(&f.channels) {
            c.sigma_source = fc.sigma_source;
        }
    }
    for d in dropped {
        match id.held.iter_mut().find(|h| h.name == d.name) {
            Some(h) => *h = d,
            None => id.held.push(d),
        }
    }
    id.conditional_on = conditional_on(&id.held);
    let delta = id.aicc.zip(full.aicc).map(|(r, f)| r - f);
    if let Some(d) = delta.filter(|&d| d > MAX_DELTA_AICC) {
        warnings.push(format!(
            "the full model fits much better than the reduced one (ΔAICc = {d:.1} > {MAX_DELTA_AICC}): the dropped terms together matter, though none is identifiable on its own; the reduced model's intervals hold only if those terms are truly negligible (a trace with larger strain, longer or with more channels pins them down)"
        ));
    }
    if !warnings.is_empty() && id.status == Status::Ok {
        id.status = Status::Warning;
    }
    id.warnings.extend(warnings);
    let fixes: Vec<String> = id
        .held
        .iter()
        .filter(|h| h.reason.is_some())
        .map(|h| match h.how {
            How::Scene => h.name.clone(),
            _ => format!("{}={}", h.name, h.value),
        })
        .collect();
    let flags = Some(format!("--fix {}", fixes.join(",")));
    id.reduction = Some(Reduction {
        full: FullFit {
            free: full.parameters.len(),
            chi2_per_dof: full.chi2_per_dof,
            aicc: full.aicc,
            status: full.status,
            not_identifiable: full
                .parameters
                .iter()
                .filter(|e| !e.identifiable)
                .map(|e| e.name.clone())
                .collect(),
        },
        rounds,
        delta_aicc: delta,
        flags,
        seconds: t0.elapsed().as_secs_f64(),
    });
    Ok(Run::Identified(Box::new(id)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::params::Space;

    fn constant(name: &str, index: usize, role: Role, start: f64) -> Constant {
        Constant {
            name: name.into(),
            unit: "Pa",
            index,
            start,
            space: Space::Linear { scale: 1.0 },
            bounds: (-100.0, 100.0),
            start_box: (-3.0, 3.0),
            role,
            mixture: None,
        }
    }

    /// The advice for a higher term names it and every higher one at 0 (what the
    /// reduction drops), an Ogden pair's α at its value, never a lower pair.
    #[test]
    fn the_advice_drops_the_term_and_every_higher_one() {
        let yeoh = [
            constant("C10", 0, Role::LeadingModulus, 7e4),
            constant("C20", 1, Role::HigherOrder, -888.0),
            constant("C30", 2, Role::HigherOrder, 16.7),
        ];
        assert_eq!(drop_advice(&yeoh, &yeoh[1]).unwrap(), "C20=0,C30=0");
        assert_eq!(drop_advice(&yeoh, &yeoh[2]).unwrap(), "C30=0");
        assert_eq!(drop_advice(&yeoh, &yeoh[0]), None);
        let ogden = [
            constant("mu1", 0, Role::LeadingModulus, 1e5),
            constant("alpha1", 1, Role::HigherOrder, 2.0),
            constant("mu2", 2, Role::HigherOrder, 1e3),
            constant("alpha2", 3, Role::HigherOrder, -2.0),
        ];
        assert_eq!(drop_advice(&ogden, &ogden[3]).unwrap(), "mu2=0,alpha2=-2");
        assert_eq!(drop_advice(&ogden, &ogden[1]), None);
    }

    /// Held constants condition the intervals unless dropped.
    #[test]
    fn dropped_terms_condition_nothing() {
        let h = |name: &str, how| Held {
            name: name.into(),
            value: 0.0,
            unit: "Pa".into(),
            how,
            reason: None,
        };
        let held = [
            h("C20", How::Dropped),
            h("eps_r", How::Scene),
            h("nv", How::Fixed),
        ];
        assert_eq!(conditional_on(&held), vec!["eps_r", "nv"]);
    }
}
