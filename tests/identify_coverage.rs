//! Coverage of `dea_fit::identify`'s 95 % intervals at the edge of what a trace shows
//! (issue 34): replicate studies on synthetic traces (`synth trace`'s machinery,
//! [`Experiment::synthetic`]) of short stack scenes with every constant free as by
//! default, then again with the fixes the tool's reasons advise (`fix NAME`, or the
//! `--fix NAME=VALUE` they spell out) applied.
//!
//! Criteria (the issue's): every constant the tool reports identifiable holds the
//! truth in at least 85 % of the replicates that report it, and the intervals of
//! all reported-identifiable constants together hold it at least 92 % of the time;
//! for the default and for the advised fixes. Binomial reasoning: if the intervals
//! are right each covers with p = 0.95, so over n = 20 replicates the count of
//! covering intervals is binomial(20, 0.95), mean 19, and P(count < 17 = 85 %) =
//! P(X ≤ 16) = 1.6 %; over all N ≈ 100–180 intervals of a scenario the count has mean
//! 0.95 N and σ = √(N·0.95·0.05) ≈ 2.2–2.9, and 92 % lies 1.4–1.7 σ below the mean
//! (a 4–8 % chance of a false alarm, which the fixed seeds turn into either always
//! or never: the counts are printed). A constant reported identifiable in fewer than
//! 20 replicates has too few to hold it to 85 %: it must not fall below the 1 %
//! lower tail of binomial(n, 0.95) ([`min_covered`]).
//!
//! Scenes are short (1 s, 200 samples) so one identification (8 starts) takes
//! about 0.2 s; the replicates run in parallel (rayon).

use super::support::{relative_noise, trace};
use dea_fit::fit::lm::Control;
use dea_fit::identify::assessment::Estimate;
use dea_fit::identify::params::{constants, set_theta, theta};
use dea_fit::identify::problem::ChannelKind;
use dea_fit::identify::{identify, reduce, Settings};
use dea_fit::sim::scene::Scene;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

/// Replicates per scenario (seeds 1000, 1001, …).
const REPLICATES: u64 = 20;

/// The seed stack (10 layers of 500 µm VHB 4910, Yeoh preset: C10, C20, C30) with
/// `arms` and a 1875 Pa·s dashpot, εr 4.7, stepped to `volts` behind a 5 ms supply
/// rise, 1 s at 200 samples.
fn stack(arms: &str, volts: &str) -> Scene {
    let text = format!(
        r#"name = "coverage"
{}
[material]
hyperelastic = {{ preset = "vhb4910-yeoh" }}
viscous = {{ nv = "1875 Pa s", arms = [ {arms} ] }}
relative_permittivity = 4.7
density = "960 kg/m3"
[source]
rise_time = "5 ms"
[[input]]
kind = "step"
amplitude = "{volts}"
[time]
span = "1 s"
samples = 200
"#,
        super::support::SEED_STACK_ACTUATOR
    );
    Scene::parse(&text, Path::new("coverage.toml")).expect("valid scene")
}

/// One replicate study: the truth, the channels with their noise, and which
/// constants the start leaves at their true value (every other starts 10 % off,
/// alternately above and below).
struct Scenario {
    name: &'static str,
    truth: Scene,
    channels: Vec<(ChannelKind, f64)>,
    start_true: &'static [&'static str],
}

/// Per constant: replicates that reported it identifiable, and how many of their
/// intervals held the truth.
#[derive(Default)]
struct Tally {
    called: usize,
    covered: usize,
}

/// The counts of one way of running (default or advised fixes) over the replicates.
#[derive(Default)]
struct Study {
    constants: BTreeMap<String, Tally>,
    /// Replicates whose identification failed or gave no result.
    failed: usize,
    /// Why the tool refused a run (an advised fix it does not accept), each once.
    refused: Vec<String>,
    /// The fixes applied, with how many replicates applied each.
    fixes: BTreeMap<String, usize>,
    /// Each interval that missed: seed, constant, estimate, interval, its kind,
    /// the truth (printed: what a next change has to explain).
    misses: Vec<String>,
}

impl Study {
    /// Count the estimates (each with its true value) of one replicate.
    fn add(&mut self, seed: u64, estimates: &[(Estimate, f64)]) {
        for (e, truth) in estimates {
            let t = self.constants.entry(e.name.clone()).or_default();
            if !e.identifiable {
                continue;
            }
            let ci = e.ci95.expect("an identifiable constant has an interval");
            t.called += 1;
            if ci[0] <= *truth && *truth <= ci[1] {
                t.covered += 1;
            } else {
                self.misses.push(format!(
                    "seed {seed}: {} = {:.5e} in [{:.5e}, {:.5e}] ({:?}), truth {:.5e}",
                    e.name, e.value, ci[0], ci[1], e.interval, truth
                ));
            }
        }
    }

    /// Print the table and return the criteria it misses.
    fn check(&self, label: &str) -> Vec<String> {
        let mut miss = Vec::new();
        println!("{label}:");
        let (mut covered, mut called) = (0, 0);
        for (name, t) in &self.constants {
            println!(
                "  {name:<9} identifiable in {:>2} of {REPLICATES}, covered {:>2} of {:>2}",
                t.called, t.covered, t.called
            );
            covered += t.covered;
            called += t.called;
            if t.covered < min_covered(t.called) {
                miss.push(format!(
                    "{label}: {name} covered {} of {}",
                    t.covered, t.called
                ));
            }
        }
        println!(
            "  all       covered {covered} of {called}; failed runs {}",
            self.failed
        );
        if !self.fixes.is_empty() {
            println!("  fixes applied: {:?}", self.fixes);
        }
        for m in &self.misses {
            println!("  missed: {m}");
        }
        // 92 % over all: covered ≥ 0.92·called, in integers.
        if 100 * covered < 92 * called {
            miss.push(format!("{label}: all covered {covered} of {called}"));
        }
        if self.failed > 0 {
            miss.push(format!("{label}: {} runs failed", self.failed));
        }
        for why in &self.refused {
            println!("  refused: {why}");
            miss.push(format!("{label}: refused: {why}"));
        }
        miss
    }
}

/// The fewest covering intervals of `n` that pass: 85 % (rounded up) when n ≥ 20;
/// below, the smallest count c with P(X < c) ≤ 1 % for X ~ binomial(n, 0.95).
fn min_covered(n: usize) -> usize {
    if n >= REPLICATES as usize {
        return (85 * n).div_ceil(100);
    }
    let pmf = |k: usize| {
        let ln_choose: f64 = (1..=k)
            .map(|i| ((n - k + i) as f64).ln() - (i as f64).ln())
            .sum();
        (ln_choose + k as f64 * 0.95f64.ln() + (n - k) as f64 * 0.05f64.ln()).exp()
    };
    let mut below = 0.0;
    for c in 0..=n {
        if below + pmf(c) > 0.01 {
            return c;
        }
        below += pmf(c);
    }
    n
}

/// The fixes the reasons of the constants not identified advise: `NAME=VALUE` where
/// a reason spells out `--fix NAME=VALUE`, else `NAME` (held at the scene's value)
/// where it says `fix NAME`. Words such as "the trace fixes only a combination"
/// advise nothing.
fn advised_fixes<'a>(estimates: impl Iterator<Item = &'a Estimate>) -> Vec<String> {
    estimates
        .filter(|e| !e.identifiable)
        .filter_map(|e| {
            let reason = e.reason.as_deref()?;
            let advice = [format!("fix {}", e.name), format!("--fix {}=", e.name)];
            let names_it = |a: &String| {
                reason.match_indices(a.as_str()).any(|(i, _)| {
                    let after = reason[i + a.len()..].chars().next();
                    a.ends_with('=') || !after.is_some_and(|c| c.is_alphanumeric() || c == '_')
                })
            };
            if !advice.iter().any(names_it) {
                return None;
            }
            let spelled = reason
                .split("--fix ")
                .nth(1)
                .and_then(|rest| rest.split([' ', ',', ')']).next())
                .filter(|f| f.starts_with(&format!("{}=", e.name)));
            Some(spelled.map_or_else(|| e.name.clone(), str::to_string))
        })
        .collect()
}

/// The outcome of one identification: its estimates with their true values, None
/// if it failed, or the error of a refused input (an advised fix the tool does not
/// accept).
type Outcome = Result<Option<Vec<(Estimate, f64)>>, String>;

/// Identify the replicate `seed` of `s`: as the command line does by default (the
/// smallest identifiable model, [`reduce::identify`]) without `fix`, else with the
/// constants in `fix` held. An arm the reduction removed takes its label from the
/// arms after it: each remaining arm is compared with the true arm of the nearest
/// relaxation time (in ln τ).
fn run(s: &Scenario, seed: u64, fix: &[String]) -> Outcome {
    let mut exp = trace(&s.truth, &s.channels, seed);
    let mut start = theta(&s.truth);
    for c in constants(&s.truth) {
        if !s.start_true.contains(&c.name.as_str()) {
            start[c.index] *= if c.index % 2 == 0 { 1.1 } else { 0.9 };
        }
    }
    set_theta(&mut exp.scene, &start);
    let settings = Settings {
        fix: fix.to_vec(),
        ..Settings::default()
    };
    let err = |e: dea_fit::Error| e.to_string();
    let run = match fix.is_empty() {
        true => reduce::identify(std::slice::from_ref(&exp), &settings, &|_| {
            Control::default()
        })
        .map_err(err)?,
        false => identify(vec![exp.clone()], &settings).map_err(err)?,
    };
    let Ok(id) = run.identified() else {
        return Ok(None);
    };
    let all = constants(&s.truth);
    let th = theta(&s.truth);
    // (k, τ) of each arm, true and as identified
    let pairs = |scene: &Scene| -> Vec<(f64, f64)> {
        let arms = &scene.material.viscous.arms;
        arms.iter().map(|a| (a.k_pa, a.eta_pa_s / a.k_pa)).collect()
    };
    let (arms, fitted) = (pairs(&s.truth), pairs(&exp.scene));
    let truth_of = |name: &str| -> f64 {
        let arm = name
            .strip_prefix("arm")
            .and_then(|r| r.split_once('.'))
            .and_then(|(j, what)| j.parse::<usize>().ok().map(|j| (j - 1, what)));
        match arm {
            Some((j, what)) if fitted.len() < arms.len() => {
                let near = |a: &(f64, f64)| (a.1.ln() - fitted[j].1.ln()).abs();
                let a = arms
                    .iter()
                    .min_by(|a, b| near(a).total_cmp(&near(b)))
                    .expect("an arm");
                match what {
                    "k" => a.0,
                    _ => a.1,
                }
            }
            _ => {
                th[all
                    .iter()
                    .find(|c| c.name == name)
                    .expect("a constant")
                    .index]
            }
        }
    };
    Ok(Some(
        id.parameters
            .into_iter()
            .map(|e| {
                let t = truth_of(&e.name);
                (e, t)
            })
            .collect(),
    ))
}

/// Run the scenario's replicates in parallel, by default and with the advised
/// fixes; print both tables and assert the criteria.
fn study(s: &Scenario) {
    // every replicate a task of its own: one that runs to the iteration limit
    // costs several others, and replicates grouped into one task leave a thread idle
    let seeds: Vec<u64> = (1000..1000 + REPLICATES).collect();
    let results: Vec<_> = seeds
        .into_par_iter()
        .with_max_len(1)
        .map(|seed| {
            let default = run(s, seed, &[]);
            let fixes = match &default {
                Ok(Some(e)) => advised_fixes(e.iter().map(|(e, _)| e)),
                _ => Vec::new(),
            };
            let fixed = match fixes.is_empty() {
                true => default.clone(),
                false => run(s, seed, &fixes),
            };
            (default, fixes, fixed)
        })
        .collect();
    let (mut default, mut advised) = (Study::default(), Study::default());
    for (seed, (d, fixes, f)) in (1000..).zip(&results) {
        for (study, outcome) in [(&mut default, d), (&mut advised, f)] {
            match outcome {
                Ok(Some(e)) => study.add(seed, e),
                Ok(None) => study.failed += 1,
                Err(why) if !study.refused.contains(why) => study.refused.push(why.clone()),
                Err(_) => {}
            }
        }
        for f in fixes {
            *advised.fixes.entry(f.clone()).or_default() += 1;
        }
    }
    let mut miss = default.check(&format!("{}, default", s.name));
    miss.extend(advised.check(&format!("{}, advised fixes", s.name)));
    assert!(miss.is_empty(), "{miss:#?}");
}

/// Noise of 1 % of the peak contraction and 0.1 % of the peak capacitance.
fn both_channels(truth: &Scene) -> Vec<(ChannelKind, f64)> {
    relative_noise(
        truth,
        &[
            (ChannelKind::Contraction, 0.01),
            (ChannelKind::Capacitance, 0.001),
        ],
    )
}

/// Small strain: a 3 kV step strains the stack by 0.32 %, where Yeoh's C20 and C30
/// are far below the noise; two arms (τ = 0.05 s and 0.3 s) and the dashpot,
/// contraction and capacitance, all nine constants free.
/// Measured (covered / reported identifiable): main 2124710, full model: 118 of
/// 131 (arm1.k 15 of 19); with id-intervals 21bbef6 and id-reduce ab11a9e, full
/// model: 124 of 129; with the default reduction (id-reduce c1bceee: C30, C20 → 0,
/// and in 7 replicates arm 2 removed): 97 of 126 (C10 13 of 20, arm1.τ 13 of 20,
/// nv 11 of 20: as many misses of C10 and arm1.τ as replicates without arm 2, so
/// probably the model without an arm the trace has biases the others; not checked
/// replicate by replicate). With the reduction limited to the hyperelastic terms
/// and εr (arms and nv kept free, reported when weak): 122 of 127 (every constant
/// ≥ 16 of 16 … 18 of 20), with the advised fixes 117 of 125; with the corrected
/// advice parser and reasons (2026-12-05): 123 of 128, and 123 of 128; with the
/// profile's second starts: 120 of 125, and 120 of 125.
#[test]
fn intervals_hold_at_small_strain() {
    let truth = stack(
        r#"{ k = "106 kPa", tau = "0.05 s" }, { k = "45 kPa", tau = "0.3 s" }"#,
        "3 kV",
    );
    study(&Scenario {
        name: "small strain",
        channels: both_channels(&truth),
        truth,
        start_true: &[],
    });
}

/// A slow arm: τ = 1 s in a 1 s trace, beside a fast one (0.05 s), at 0.9 % strain
/// (5 kV); contraction and capacitance, all nine constants free.
/// Measured: main 2124710, full model: 95 of 102, with the advised fixes 78 of 89
/// (C10 10 of 13, εr 12 of 15); with id-intervals 21bbef6 and id-reduce ab11a9e,
/// full model: 87 of 99 (arm1.k and arm1.τ 16 of 20); with the default reduction
/// of id-reduce c1bceee (the slow arm removed in 19 of 20 replicates): 28 of 87 (C10
/// 0 of 17, arm1.τ 0 of 18, nv 6 of 18): without the slow arm, C10 and the fast
/// arm carry its stiffness and their intervals exclude the true values. With the
/// reduction limited to the hyperelastic terms and εr (arms kept): 72 of 80
/// (90 %, arm1.τ 15 of 18; C10 identifiable in 7 of 20), with the advised fixes 70
/// of 78. With the advice parser corrected and reasons that advise no guessed fix
/// (2026-12-05): 74 of 81 (91.4 %: arm1.k 16 of 18, arm1.τ 15 of 18), advised
/// fixes 74 of 83; with steep or failed profile re-fits re-fitted from a second
/// start: 66 of 72 (91.7 %: arm1.k 14 of 18, arm1.τ 18 of 18), advised fixes 68 of
/// 72: below the 92 % overall. Two of those arm1.k misses (seeds 1001, 1014)
/// came from searches that stopped at the iteration limit with C20 and C30 on
/// their search bounds (the profile at the truth, re-fitted by hand from the
/// stopping point, rose by only 0.5–2.5); the other two are the likelihood's own
/// (Δχ² at the truth 4.3 and 4.7, re-fitted from several starts). With a search
/// that did not converge reporting nothing identifiable (2026-12-06; 5 of 20
/// replicates here): 59 of 63 (93.7 %: arm1.k 13 of 15), advised fixes 59 of 63.
#[test]
fn intervals_hold_with_an_arm_as_slow_as_the_trace() {
    let truth = stack(
        r#"{ k = "106 kPa", tau = "0.05 s" }, { k = "45 kPa", tau = "1 s" }"#,
        "5 kV",
    );
    study(&Scenario {
        name: "slow arm",
        channels: both_channels(&truth),
        truth,
        start_true: &[],
    });
}

/// Contraction only (εr then cannot be separated from the moduli): one arm and the
/// dashpot at 0.9 % strain. The scene's εr is the truth (the value a user who
/// measures no capacitance must state); every other constant starts off.
/// On main the tool refused its own advice here (`--fix nv=0`: "nv must be finite
/// and positive"); with id-intervals and id-reduce merged one study ran for more
/// than 5 CPU-minutes (profiles of the correlated moduli in every round of the
/// reduction) without ending. With εr held first and the arms kept: 78 of 80, the
/// same with the advised fixes.
#[test]
fn intervals_hold_from_contraction_alone() {
    let truth = stack(r#"{ k = "106 kPa", tau = "0.1 s" }"#, "5 kV");
    study(&Scenario {
        name: "contraction only",
        channels: relative_noise(&truth, &[(ChannelKind::Contraction, 0.01)]),
        truth,
        start_true: &["eps_r"],
    });
}
