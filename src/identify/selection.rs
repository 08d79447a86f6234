//! Model no more than the traces need: `--arms auto` fits 0 … [`MAX_ARMS`] Maxwell
//! arms, `--hyperelastic auto` the invariant hyperelastic models
//! ([`HYPERELASTIC_MODELS`]) in place of the scene's, and both together every pair
//! of them (a joint choice: the fewer constants of one part may be paid for by the
//! other). The candidate kept is the one with the fewest free constants whose AICc
//! is within [`DELTA_AICC`] of the smallest, among the candidates whose status does
//! not block (a redundant arm or polynomial term is not identifiable, so its
//! candidate is `ill_posed` and not eligible); equal counts go to the smaller AICc.
//! The rule is the one `dea-fit hyperelastic --model auto` applies (Burnham &
//! Anderson 2002: models within ΔAICc ≤ 2 have substantial support).
//!
//! The criteria compare χ² of one data set, so every candidate must weigh the
//! residuals with the same σ: the candidate with the most constants is fitted
//! first (σ of the channels not given estimated from its residuals; if it cannot
//! be fitted, the next largest), and its σ are given to the others. A candidate
//! that cannot be fitted (no start simulates the traces with its material) is a
//! `failed` row.
//!
//! Starts of the candidates' constants: arms at relaxation times spread
//! geometrically from 5 sample intervals to half the longest trace (the time scales
//! a trace can show), their springs sharing the scene's total arm stiffness (μ0
//! without arms). A hyperelastic model starts at the scene's small-strain modulus
//! μ0 (at its own values when it is the scene's model), each term beyond the
//! leading one carrying a share s = [`HIGHER_TERM_SHARE`] of the leading term's
//! stress at the largest x = I1 − 3 the scene's own run of the traces reaches
//! (at least [`MIN_REACH`]): neo-Hookean μ = μ0; Mooney-Rivlin C10 = (1 − s)·μ0/2,
//! C01 = s·μ0/2; Yeoh C10 = μ0/2, C20 = s·C10/(2x), C30 = s·C10/(3x²); Gent μ = μ0,
//! Jm = x/s. A term that starts at zero would be searched only within ±0.1·μ0
//! ([`super::params`]), too narrow for a strongly stiffening material; starting it
//! at a share of what the traces can show scales its search box to them (a
//! stiffening start also keeps the softer candidates off pull-in).

use super::noise::Sigma;
use super::problem::Experiment;
use super::{identify_with, Identification, Run, Settings};
use crate::error::{Error, Result};
use crate::fit::lm::Control;
use crate::material::file::Arm;
use crate::material::hyperelastic::{ModelSpec, OgdenForm};
use serde::Serialize;
use std::sync::Arc;

/// Most arms `--arms auto` tries.
pub const MAX_ARMS: usize = 4;

/// The models `--hyperelastic auto` tries: the invariant-based ones, fewest
/// parameters first (Ogden, stretch-based, is left to `dea-fit hyperelastic`).
pub const HYPERELASTIC_MODELS: [&str; 4] = ["neo-hookean", "mooney-rivlin", "gent", "yeoh"];

/// Share of the leading term's stress each further term of a candidate model starts
/// with, at the largest I1 − 3 of the traces (module documentation).
pub const HIGHER_TERM_SHARE: f64 = 0.05;

/// Smallest I1 − 3 the starts are scaled to (a trace at a smaller strain would
/// start the Yeoh terms beyond the plausible stress coefficients).
pub const MIN_REACH: f64 = 0.01;

/// AICc margin within which the candidate with fewer constants is preferred.
pub const DELTA_AICC: f64 = 2.0;

/// What a selection chooses.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Choose {
    /// The number of Maxwell arms (`--arms auto`).
    pub arms: bool,
    /// The hyperelastic model (`--hyperelastic auto`).
    pub hyperelastic: bool,
}

/// One candidate of the comparison.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    /// Hyperelastic model.
    pub model: String,
    /// Number of arms.
    pub arms: usize,
    /// Free constants.
    pub free: usize,
    /// χ²/(N − p) at the common σ (None for a candidate without a fit).
    pub chi2_per_dof: Option<f64>,
    /// AICc (None when undefined).
    pub aicc: Option<f64>,
    /// AICc minus the smallest AICc of the eligible candidates (None when either is
    /// undefined).
    pub delta_aicc: Option<f64>,
    /// BIC (None for a candidate without a fit).
    pub bic: Option<f64>,
    /// Its status: `failed` when no start could simulate the traces with its
    /// material (a model that pulls in under the drive at every start).
    pub status: crate::fit::Status,
    /// Why it failed (None otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub failure: Option<String>,
    /// Eligible (a status that does not block, AICc defined).
    pub eligible: bool,
}

/// The comparison a selection made.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// What it chose.
    pub choose: Choose,
    /// Every candidate, in the order tried (models as listed, arms ascending).
    pub candidates: Vec<Candidate>,
    /// Index of the chosen candidate.
    pub chosen: usize,
    /// Index of the candidate whose σ all used.
    pub sigma_from: usize,
}

/// A candidate fitted: its identification and its experiments.
type Fitted = (Identification, Vec<Experiment>);

/// The material one candidate puts into the scenes.
#[derive(Clone)]
struct Material {
    spec: ModelSpec,
    params: Vec<f64>,
    arms: Vec<Arm>,
}

/// The arms of an `n`-arm candidate for `experiments` (module documentation).
fn arms(experiments: &[Experiment], n: usize) -> Vec<Arm> {
    let scene = &experiments[0].scene;
    let m = &scene.material;
    let total = match m.viscous.arms.iter().map(|a| a.k_pa).sum::<f64>() {
        k if k > 0.0 => k,
        _ => m.model.initial_shear_modulus(&m.params).abs(),
    };
    let dt = experiments
        .iter()
        .flat_map(|e| e.scene.time.samples.windows(2).map(|w| w[1] - w[0]))
        .fold(f64::INFINITY, f64::min);
    let span = experiments
        .iter()
        .map(|e| e.scene.time.span)
        .fold(0.0, f64::max);
    let (lo, hi) = (5.0 * dt, 0.5 * span);
    (0..n)
        .map(|j| {
            let f = if n == 1 {
                0.5
            } else {
                j as f64 / (n - 1) as f64
            };
            let tau = lo * (hi / lo).powf(f);
            let k = total / n as f64;
            Arm {
                k_pa: k,
                eta_pa_s: k * tau,
            }
        })
        .collect()
}

/// The starting parameters of model `name` on `scene` for traces that reach
/// I1 − 3 = `x` (module documentation).
fn model_start(scene: &crate::sim::scene::Scene, name: &str, x: f64) -> Vec<f64> {
    let m = &scene.material;
    if m.spec.name == name {
        return m.params.clone();
    }
    let mu0 = m.model.initial_shear_modulus(&m.params);
    let s = HIGHER_TERM_SHARE;
    match name {
        "neo-hookean" => vec![mu0],
        "mooney-rivlin" => vec![(1.0 - s) * 0.5 * mu0, s * 0.5 * mu0],
        "gent" => vec![mu0, x / s],
        _ => {
            let c10 = 0.5 * mu0;
            vec![c10, s * c10 / (2.0 * x), s * c10 / (3.0 * x * x)]
        }
    }
}

/// The largest I1 − 3 the scenes of `experiments` reach with their own material
/// (up to a pull-in, if they pull in), at least [`MIN_REACH`].
fn reach(experiments: &[Experiment]) -> Result<f64> {
    let mut x = MIN_REACH;
    for e in experiments {
        let mode = crate::sim::full_plant(&e.scene)?.mode;
        let o = crate::sim::trajectory(&e.scene, &crate::sim::RunOptions::default())?;
        for s in &o.samples {
            let i1 = mode.kinematics(s.stretch).invariants().0;
            if i1.is_finite() {
                x = x.max(i1 - 3.0);
            }
        }
    }
    Ok(x)
}

/// The names of the parameters of the scene's model and of every model
/// `--hyperelastic auto` tries.
fn hyperelastic_names(scene: &crate::sim::scene::Scene) -> Result<Vec<String>> {
    let mut names: Vec<String> = Vec::new();
    let mut add = |spec: &ModelSpec| -> Result<()> {
        for p in spec.build()?.params() {
            if !names.contains(&p.name) {
                names.push(p.name.clone());
            }
        }
        Ok(())
    };
    add(&scene.material.spec)?;
    for m in HYPERELASTIC_MODELS {
        add(&ModelSpec::new(m, OgdenForm::Abaqus))?;
    }
    Ok(names)
}

/// Refuse `--free`/`--fix` names of the constants the selection chooses.
fn refuse_chosen_names(
    experiments: &[Experiment],
    settings: &Settings,
    choose: Choose,
) -> Result<()> {
    let named: Vec<&str> = settings
        .fix
        .iter()
        .map(|f| f.split_once('=').map_or(f.as_str(), |(n, _)| n).trim())
        .chain(settings.free.iter().flatten().map(|n| n.trim()))
        .collect();
    if choose.arms {
        if let Some(n) = named.iter().find(|n| n.starts_with("arm")) {
            return Err(Error::settings(format!(
                "--arms auto chooses the arms: --free and --fix cannot name arm constants ({n})"
            ))
            .with_hint(
                "drop the armN names, or give the arms in the scene and leave out --arms auto",
            ));
        }
    }
    if choose.hyperelastic {
        let hyper = hyperelastic_names(&experiments[0].scene)?;
        if let Some(n) = named.iter().find(|n| hyper.iter().any(|h| h == *n)) {
            return Err(Error::settings(format!(
                "--hyperelastic auto chooses the hyperelastic model: --free and --fix cannot name its constants ({n})"
            ))
            .with_hint(format!(
                "drop {n}, or give the model in the scene and leave out --hyperelastic auto"
            )));
        }
    }
    Ok(())
}

/// The candidates' materials: every model tried × every number of arms tried, the
/// models' starts scaled to traces that reach I1 − 3 = `x`.
fn candidates(experiments: &[Experiment], choose: Choose, x: f64) -> Vec<Material> {
    let scene = &experiments[0].scene;
    let m = &scene.material;
    let models: Vec<String> = match choose.hyperelastic {
        true => HYPERELASTIC_MODELS.iter().map(|s| s.to_string()).collect(),
        false => vec![m.spec.name.clone()],
    };
    let counts: Vec<usize> = match choose.arms {
        true => (0..=MAX_ARMS).collect(),
        false => vec![m.viscous.arms.len()],
    };
    let mut out = Vec::new();
    for name in &models {
        for &n in &counts {
            let same = *name == m.spec.name;
            out.push(Material {
                spec: match same {
                    true => m.spec.clone(),
                    false => ModelSpec::new(name, OgdenForm::Abaqus),
                },
                params: model_start(scene, name, x),
                arms: match choose.arms {
                    true => arms(experiments, n),
                    false => m.viscous.arms.clone(),
                },
            });
        }
    }
    out
}

/// `experiments` with the candidate's material (its model, starting values and
/// arms; the fitted ranges of the scene's file kept only for the same model).
fn with_material(experiments: &[Experiment], c: &Material) -> Result<Vec<Experiment>> {
    let model: Arc<dyn crate::material::hyperelastic::StrainEnergy> = Arc::from(c.spec.build()?);
    Ok(experiments
        .iter()
        .cloned()
        .map(|mut e| {
            let m = &mut e.scene.material;
            if m.spec != c.spec {
                m.fit = None;
            }
            m.spec = c.spec.clone();
            m.model = model.clone();
            m.params = c.params.clone();
            m.viscous.arms = c.arms.clone();
            e
        })
        .collect())
}

/// The settings of a candidate: a `--free` list gains the constants the selection
/// chooses (the model's parameters, the arms), and no profiles (they are computed
/// for the chosen candidate only).
fn settings_for(s: &Settings, c: &Material, choose: Choose) -> Result<Settings> {
    let mut s = s.clone();
    s.profiles.clear();
    if let Some(list) = &mut s.free {
        if choose.hyperelastic {
            list.extend(c.spec.build()?.params().iter().map(|p| p.name.clone()));
        }
        if choose.arms {
            for j in 1..=c.arms.len() {
                list.push(format!("arm{j}.k"));
                list.push(format!("arm{j}.tau"));
            }
        }
    }
    Ok(s)
}

/// The number of constants candidate `c` frees under `s`.
fn free_count(
    experiments: &[Experiment],
    c: &Material,
    s: &Settings,
    choose: Choose,
) -> Result<usize> {
    let exps = with_material(&experiments[..1], c)?;
    let s = settings_for(s, c, choose)?;
    let all = super::params::constants(&exps[0].scene);
    Ok(super::params::choose(&all, s.free.as_deref(), &s.fix)?
        .free
        .len())
}

/// Fit every candidate and choose (module documentation): the chosen candidate's
/// identification, its experiments (the scenes with its model and arms) and the
/// comparison.
pub fn select(
    experiments: Vec<Experiment>,
    settings: &Settings,
    choose: Choose,
    control: &(dyn Fn(usize) -> Control + Sync),
) -> Result<(Identification, Vec<Experiment>, Comparison)> {
    if experiments.is_empty() {
        return Err(Error::settings("no trace to identify from"));
    }
    refuse_chosen_names(&experiments, settings, choose)?;
    let x = match choose.hyperelastic {
        true => reach(&experiments)?,
        false => MIN_REACH,
    };
    let mats = candidates(&experiments, choose, x);
    let run = |c: &Material, s: &Settings| -> Result<Fitted> {
        let exps = with_material(&experiments, c)?;
        let label = format!("candidate {}, {} arm(s)", c.spec.name, c.arms.len());
        let id = identified(identify_with(
            exps.clone(),
            &settings_for(s, c, choose)?,
            &|i| Control {
                label: Some(label.clone()),
                ..control(i)
            },
        )?)?;
        Ok((id, exps))
    };
    // Largest first until one can be fitted: its σ are the common σ. When none can,
    // the largest candidate's error is the selection's (an error of the traces or
    // settings shows there first).
    let size = |c: &Material| c.params.len() + 2 * c.arms.len();
    let mut order: Vec<usize> = (0..mats.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(size(&mats[i])));
    let mut fits: Vec<Option<Result<Fitted>>> = (0..mats.len()).map(|_| None).collect();
    let mut common = settings.clone();
    let mut sigma_from = None;
    for &i in &order {
        let f = run(&mats[i], settings);
        if let Ok((id, _)) = &f {
            for e in &id.experiments {
                for c in &e.channels {
                    if !common.sigma.iter().any(|(k, _)| *k == c.channel) {
                        common.sigma.push((c.channel, Sigma::Absolute(c.sigma)));
                    }
                }
            }
            sigma_from = Some(i);
        }
        fits[i] = Some(f);
        if sigma_from.is_some() {
            break;
        }
    }
    let Some(sigma_from) = sigma_from else {
        return match fits[order[0]].take() {
            Some(Err(e)) => Err(e),
            _ => Err(Error::settings(format!("{}: no candidate", flags(choose)))),
        };
    };
    let mut fits: Vec<Result<Fitted>> = fits
        .into_iter()
        .zip(&mats)
        .map(|(f, c)| f.unwrap_or_else(|| run(c, &common)))
        .collect();
    let mut table: Vec<Candidate> = fits
        .iter()
        .zip(&mats)
        .map(|(f, c)| {
            let mut row = Candidate {
                model: c.spec.name.clone(),
                arms: c.arms.len(),
                free: free_count(&experiments, c, &common, choose)?,
                chi2_per_dof: None,
                aicc: None,
                delta_aicc: None,
                bic: None,
                status: crate::fit::Status::Failed,
                failure: None,
                eligible: false,
            };
            match f {
                Ok((f, _)) => {
                    row.chi2_per_dof = Some(f.chi2_per_dof);
                    row.aicc = f.aicc;
                    row.bic = Some(f.bic);
                    row.status = f.status;
                    row.eligible = !f.status.is_blocking() && f.aicc.is_some();
                }
                Err(e) => row.failure = Some(e.to_string()),
            }
            Ok(row)
        })
        .collect::<Result<_>>()?;
    let best = table
        .iter()
        .filter(|c| c.eligible)
        .filter_map(|c| c.aicc)
        .fold(f64::INFINITY, f64::min);
    for c in &mut table {
        c.delta_aicc = c.aicc.map(|a| a - best).filter(|d| d.is_finite());
    }
    let chosen = (0..table.len())
        .filter(|&i| table[i].eligible && table[i].delta_aicc.is_some_and(|d| d <= DELTA_AICC))
        .min_by(|&a, &b| {
            let (a, b) = (&table[a], &table[b]);
            a.free
                .cmp(&b.free)
                .then(a.delta_aicc.unwrap_or(0.0).total_cmp(&b.delta_aicc.unwrap_or(0.0)))
        })
        .ok_or_else(|| {
            Error::settings(format!(
                "{}: no candidate ({} fitted) is identifiable from these traces",
                flags(choose),
                table.len()
            ))
            .with_hint("fix more constants, measure more channels, or give the model and arms in the scene")
        })?;
    let (mut id, exps) = fits.swap_remove(chosen)?;
    if !settings.profiles.is_empty() {
        let mut s = settings_for(&common, &mats[chosen], choose)?;
        s.profiles = settings.profiles.clone();
        id = identified(identify_with(exps.clone(), &s, control)?)?;
    }
    Ok((
        id,
        exps,
        Comparison {
            choose,
            candidates: table,
            chosen,
            sigma_from,
        },
    ))
}

/// A candidate's identification, or its failure (no start could simulate the
/// traces with its material) as the error its row reports.
fn identified(run: Run) -> Result<Identification> {
    run.identified()
        .map_err(|f| Error::settings(f.reason.clone()).with_hint(f.hint.clone()))
}

/// The flags of a selection, as the user wrote them.
pub fn flags(choose: Choose) -> &'static str {
    match (choose.hyperelastic, choose.arms) {
        (true, true) => "--hyperelastic auto --arms auto",
        (true, false) => "--hyperelastic auto",
        _ => "--arms auto",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped damped stack (Yeoh, four arms) as an experiment without channels.
    fn experiment() -> Experiment {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("datasets/scenes/stack_step_5kV_damped.toml");
        Experiment {
            name: "stack".into(),
            scene: crate::sim::scene::Scene::read(&path).expect("shipped scene"),
            channels: Vec::new(),
        }
    }

    /// Both selections together try every model with every number of arms; the
    /// candidate with the most constants (whose σ the others use) is Yeoh with four
    /// arms; the scene's own model starts at its own values, the others at its μ0
    /// with their further terms at the stated share of the leading one at x.
    #[test]
    fn the_joint_grid_is_every_model_with_every_arm_count() {
        let e = vec![experiment()];
        let both = Choose {
            arms: true,
            hyperelastic: true,
        };
        let x = 0.3;
        let c = candidates(&e, both, x);
        assert_eq!(c.len(), HYPERELASTIC_MODELS.len() * (MAX_ARMS + 1));
        let size = |m: &Material| m.params.len() + 2 * m.arms.len();
        let big = c.iter().max_by_key(|m| size(m)).unwrap();
        assert_eq!((big.spec.name.as_str(), big.arms.len()), ("yeoh", 4));
        let m = &e[0].scene.material;
        assert_eq!(big.params, m.params);
        let mu0 = m.model.initial_shear_modulus(&m.params);
        assert_eq!(c[0].spec.name, "neo-hookean");
        assert_eq!(c[0].params, vec![mu0]);
        let by_name = |n: &str| c.iter().find(|m| m.spec.name == n).unwrap();
        let mr = &by_name("mooney-rivlin").params;
        assert!((2.0 * (mr[0] + mr[1]) - mu0).abs() < 1e-9 * mu0, "{mr:?}");
        assert!((mr[1] / mr[0] - HIGHER_TERM_SHARE / (1.0 - HIGHER_TERM_SHARE)).abs() < 1e-12);
        let gent = &by_name("gent").params;
        assert_eq!(gent, &vec![mu0, x / HIGHER_TERM_SHARE]);
        let hyper_only = Choose {
            arms: false,
            hyperelastic: true,
        };
        let h = candidates(&e, hyper_only, x);
        assert_eq!(h.len(), HYPERELASTIC_MODELS.len());
        assert!(h.iter().all(|m| m.arms == e[0].scene.material.viscous.arms));
    }

    /// `--free`/`--fix` may not name what the selection chooses (any candidate
    /// model's parameters, arm constants), and say so by name.
    #[test]
    fn chosen_constants_cannot_be_named() {
        let e = vec![experiment()];
        let hyper = Choose {
            arms: false,
            hyperelastic: true,
        };
        for (free, fix) in [
            (None, vec!["C01".to_string()]),
            (Some(vec!["mu".to_string()]), vec![]),
        ] {
            let s = Settings {
                free,
                fix,
                ..Settings::default()
            };
            let err = refuse_chosen_names(&e, &s, hyper).unwrap_err().to_string();
            assert!(err.contains("--hyperelastic auto chooses"), "{err}");
        }
        let s = Settings {
            fix: vec!["arm1.k=5e4".into()],
            ..Settings::default()
        };
        assert!(refuse_chosen_names(&e, &s, hyper).is_ok());
        let arms = Choose {
            arms: true,
            hyperelastic: false,
        };
        let err = refuse_chosen_names(&e, &s, arms).unwrap_err().to_string();
        assert!(err.contains("arm1.k"), "{err}");
    }
}
