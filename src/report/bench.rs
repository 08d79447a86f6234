//! Report of `dea-fit bench hyperelastic`: the rows as CSV, speed-vs-accuracy
//! charts as SVG, and a Markdown page linking them with the headline figures.

use super::format::si;
use super::page::{code, link, strong, text, Page};
use super::plot::{Chart, Series, Style};
use super::runs::Run;
use crate::bench::{HyperRow, Study, TRELOAR_ALL, VHB_UNIAXIAL};
use crate::error::{Error, Result};
use crate::fit::Status;
use crate::io::write::atomic_write;
use std::path::{Path, PathBuf};

/// CSV of the rows (one line per case, header from [`HyperRow`]'s fields).
pub fn csv(rows: &[HyperRow]) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r)
            .map_err(|e| Error::settings(format!("could not write the CSV: {e}")))?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| Error::settings(format!("could not write the CSV: {e}")))?;
    String::from_utf8(bytes).map_err(|e| Error::settings(format!("CSV is not UTF-8: {e}")))
}

fn find<'a>(rows: &'a [HyperRow], study: Study, dataset: &str, model: &str) -> Vec<&'a HyperRow> {
    rows.iter()
        .filter(|r| r.study == study && r.dataset == dataset && r.model == model)
        .collect()
}

/// The headline figures, one sentence each (the aims: a Yeoh uniaxial fit in
/// microseconds, the Ogden-3 three-mode Treloar fit well under 50 ms on one core).
pub fn headline(rows: &[HyperRow]) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(r) = find(rows, Study::Models, VHB_UNIAXIAL, "yeoh").first() {
        out.push(format!(
            "Yeoh on {VHB_UNIAXIAL}: {} per fit (median of {}; search alone {}), RMSE {}",
            si(r.fit_median_s, "s"),
            r.repeats,
            si(r.solver_median_s, "s"),
            si(r.rmse_pa, "Pa")
        ));
    }
    if let Some(r) = find(rows, Study::Models, TRELOAR_ALL, "ogden3").first() {
        out.push(format!(
            "Ogden-3 on {TRELOAR_ALL}: {} per fit (median of {}; search alone {}), RMSE {}, {} of {} starts at the best objective",
            si(r.fit_median_s, "s"),
            r.repeats,
            si(r.solver_median_s, "s"),
            si(r.rmse_pa, "Pa"),
            r.starts_at_best,
            r.starts
        ));
    }
    let method = find(rows, Study::Method, TRELOAR_ALL, "ogden3");
    let vp = method.iter().find(|r| r.value == "varpro");
    let full = method.iter().find(|r| r.value == "full");
    if let (Some(v), Some(f)) = (vp, full) {
        out.push(format!(
            "Ogden-3 on {TRELOAR_ALL}, variable projection vs full LM from the same {} starts: {} vs {} of the search ({:.1}× faster), {} vs {} starts at the best objective, objective {:.6e} vs {:.6e}",
            v.starts,
            si(v.solver_median_s, "s"),
            si(f.solver_median_s, "s"),
            f.solver_median_s / v.solver_median_s,
            v.starts_at_best,
            f.starts_at_best,
            v.objective,
            f.objective
        ));
    }
    out
}

/// Write `hyperelastic.csv`, the `hyperelastic-*.svg` charts and the page
/// (`hyperelastic.md`, `hyperelastic.html`, `hyperelastic.run.json`) into `dir`;
/// returns the HTML page. `note` (e.g. the measurement budget and machine)
/// goes under the title.
pub fn write_hyperelastic(rows: &[HyperRow], note: &str, dir: &Path) -> Result<PathBuf> {
    atomic_write(&dir.join("hyperelastic.csv"), csv(rows)?.as_bytes())?;
    let status = rows.iter().fold(Status::Ok, |s, r| {
        crate::fit::permittivity::worst(s, r.status)
    });
    let mut page = Page::new("Hyperelastic estimator: speed against accuracy");
    page.text(note);
    page.status_line(status, status);
    page.para(vec![
        text("All rows: "),
        link("hyperelastic.csv", "hyperelastic.csv"),
        text(". Times are wall clock on one thread, median over repeated runs; "),
        strong("fit"),
        text(" is the whole "),
        code("fit::hyperelastic::fit"),
        text(" call (search, uncertainty, Drucker check, extrapolation), "),
        strong("search"),
        text(" the estimator alone. The objective is ½‖r‖² of the absolute residuals (Pa²)."),
    ]);
    page.heading("Headline");
    let headlines = headline(rows);
    page.bullets(headlines.iter().cloned());

    // Models: one chart per dataset.
    page.heading("Every model on the shipped data");
    let mut datasets: Vec<&str> = Vec::new();
    for r in rows.iter().filter(|r| r.study == Study::Models) {
        if !datasets.contains(&r.dataset.as_str()) {
            datasets.push(&r.dataset);
        }
    }
    for d in &datasets {
        let sel: Vec<&HyperRow> = rows
            .iter()
            .filter(|r| r.study == Study::Models && r.dataset == *d)
            .collect();
        let name = format!("hyperelastic-models-{d}.svg");
        let chart = Chart {
            title: format!("{d}: fit time vs RMSE"),
            x_label: "median time per fit (log)".into(),
            y_label: "RMSE".into(),
            series: sel
                .iter()
                .enumerate()
                .map(|(i, r)| Series {
                    label: r.model.clone(),
                    points: vec![(r.fit_median_s, r.rmse_pa)],
                    color: i,
                    style: Style::Points,
                })
                .collect(),
            log_x: true,
            x_unit: Some("s".into()),
            y_unit: Some("Pa".into()),
        };
        page.subheading(d.to_string());
        page.chart(dir, &name, d, &chart)?;
        let body: Vec<Vec<String>> = sel
            .iter()
            .map(|r| {
                vec![
                    r.model.clone(),
                    si(r.fit_median_s, "s"),
                    si(r.fit_min_s, "s"),
                    si(r.solver_median_s, "s"),
                    r.repeats.to_string(),
                    si(r.rmse_pa, "Pa"),
                    format!("{}/{}", r.starts_at_best, r.starts),
                    r.status.to_string(),
                ]
            })
            .collect();
        page.table(
            &[
                "model",
                "fit (median)",
                "fit (min)",
                "search",
                "runs",
                "RMSE",
                "starts at best",
                "status",
            ],
            body,
        );
    }

    // Sweeps of one setting on Ogden-3 / Treloar.
    for (study, file, title, setting, what) in [
        (
            Study::Starts,
            "hyperelastic-starts.svg",
            "multi-start points",
            "Settings::max_starts",
            "the first N of the deterministic start list",
        ),
        (
            Study::Tolerance,
            "hyperelastic-ftol.svg",
            "LM cost tolerance",
            "Settings::ftol",
            "relative cost decrease at which each LM search stops",
        ),
    ] {
        let sel: Vec<&HyperRow> = rows.iter().filter(|r| r.study == study).collect();
        if sel.is_empty() {
            continue;
        }
        let best = sel
            .iter()
            .map(|r| r.objective)
            .fold(f64::INFINITY, f64::min);
        let ppm = |o: f64| 1e6 * (o - best) / best;
        let mut series: Vec<Series> = sel
            .iter()
            .enumerate()
            .map(|(i, r)| Series {
                label: format!("{} = {}", r.setting, r.value),
                points: vec![(r.fit_median_s, ppm(r.objective))],
                color: i,
                style: Style::Points,
            })
            .collect();
        series.push(Series {
            label: "in order".into(),
            points: sel
                .iter()
                .map(|r| (r.fit_median_s, ppm(r.objective)))
                .collect(),
            color: 7,
            style: Style::Dashed,
        });
        let chart = Chart {
            title: format!("Ogden-3, {TRELOAR_ALL}: {title}, objective vs time"),
            x_label: "median time per fit (log)".into(),
            y_label: "objective above the best reached [ppm]".into(),
            series,
            log_x: true,
            x_unit: Some("s".into()),
            y_unit: None,
        };
        page.heading(format!("Ogden-3 on {TRELOAR_ALL}: {title}"));
        page.para(vec![
            text("Varied: "),
            code(setting),
            text(format!(" ({what}).")),
        ]);
        page.chart(dir, file, title, &chart)?;
        let body: Vec<Vec<String>> = sel
            .iter()
            .map(|r| {
                vec![
                    r.value.clone(),
                    si(r.fit_median_s, "s"),
                    si(r.solver_median_s, "s"),
                    format!("{:.6e}", r.objective),
                    format!("{:.2e}", (r.objective - best) / best),
                    si(r.rmse_pa, "Pa"),
                    format!("{}/{}", r.starts_at_best, r.starts),
                    r.iterations.to_string(),
                    r.status.to_string(),
                ]
            })
            .collect();
        page.table(
            &[
                &sel[0].setting,
                "fit (median)",
                "search",
                "objective",
                "excess over best",
                "RMSE",
                "starts at best",
                "iterations",
                "status",
            ],
            body,
        );
    }

    // Variable projection vs full LM.
    let sel: Vec<&HyperRow> = rows.iter().filter(|r| r.study == Study::Method).collect();
    if !sel.is_empty() {
        let file = "hyperelastic-method.svg";
        let point = |r: &HyperRow| {
            (
                r.solver_median_s,
                100.0 * r.starts_at_best as f64 / r.starts.max(1) as f64,
            )
        };
        let mut models: Vec<&str> = Vec::new();
        for r in &sel {
            if !models.contains(&r.model.as_str()) {
                models.push(&r.model);
            }
        }
        // One dashed segment per model from its varpro point to its full-LM point.
        let links = models.iter().enumerate().map(|(i, m)| Series {
            label: format!("{m}: varpro → full"),
            points: sel
                .iter()
                .filter(|r| r.model == *m)
                .map(|r| point(r))
                .collect(),
            color: 2 + i,
            style: Style::Dashed,
        });
        let series = [("varpro", "variable projection"), ("full", "full LM")]
            .iter()
            .enumerate()
            .map(|(i, (v, label))| Series {
                label: label.to_string(),
                points: sel
                    .iter()
                    .filter(|r| r.value == *v)
                    .map(|r| point(r))
                    .collect(),
                color: i,
                style: Style::Points,
            })
            .chain(links)
            .collect();
        let chart = Chart {
            title: format!("{TRELOAR_ALL}: variable projection vs full LM, same starts"),
            x_label: "median search time (log)".into(),
            y_label: "starts ending at the best objective [%]".into(),
            series,
            log_x: true,
            x_unit: Some("s".into()),
            y_unit: None,
        };
        page.heading(format!("Variable projection vs full LM on {TRELOAR_ALL}"));
        page.para(vec![
            text(
                "Both search from the same starts: the exponents from the model's start list, \
                 the linear coefficients solved exactly at them (",
            ),
            code("Settings::method"),
            text(
                "); both end with the same full-parameter polish. \"Starts at best\" counts the \
                 starts whose search ended within 1e-6 (relative) of that run's best objective; \
                 compare the objectives to see that both runs found the same best.",
            ),
        ]);
        page.chart(dir, file, "method", &chart)?;
        let body: Vec<Vec<String>> = sel
            .iter()
            .map(|r| {
                vec![
                    r.model.clone(),
                    r.value.clone(),
                    si(r.solver_median_s, "s"),
                    si(r.fit_median_s, "s"),
                    format!("{:.6e}", r.objective),
                    format!("{}/{}", r.starts_at_best, r.starts),
                    r.iterations.to_string(),
                    r.evaluations.to_string(),
                    r.status.to_string(),
                ]
            })
            .collect();
        page.table(
            &[
                "model",
                "method",
                "search",
                "fit",
                "objective",
                "starts at best",
                "iterations",
                "evaluations",
                "status",
            ],
            body,
        );
    }
    let mut inputs: Vec<&str> = Vec::new();
    for r in rows {
        if !inputs.contains(&r.dataset.as_str()) {
            inputs.push(&r.dataset);
        }
    }
    // The run list shows the time per fit of the two headline cases only.
    let short: Vec<String> = [
        (VHB_UNIAXIAL, "yeoh", "Yeoh"),
        (TRELOAR_ALL, "ogden3", "Ogden-3"),
    ]
    .iter()
    .filter_map(|&(d, m, name)| {
        find(rows, Study::Models, d, m)
            .first()
            .map(|r| format!("{name} on {d}: {} per fit", si(r.fit_median_s, "s")))
    })
    .collect();
    let run = Run::new("bench hyperelastic", inputs.join(", "), "every model").headline(short);
    page.write(dir, "hyperelastic", run)
}

#[cfg(test)]
mod tests {
    /// One spelling of each status everywhere: no string literal of the sources
    /// (messages, help, bench pages, the run index) spells a fit's status another
    /// way than its `Display` does (`ill_posed`, `not_converged`, `not_validated`,
    /// `pull_in`): never "ill-posed", "ill posed", "not converged", "pull-in state".
    #[test]
    fn statuses_have_one_spelling() {
        let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut stack = vec![src];
        let mut found = Vec::new();
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap().flatten() {
                let p = e.path();
                if p.is_dir() {
                    stack.push(p);
                    continue;
                }
                if p.extension().is_none_or(|x| x != "rs") {
                    continue;
                }
                let text = std::fs::read_to_string(&p).unwrap();
                for (n, line) in text.lines().enumerate() {
                    let code = line.trim_start();
                    if code.starts_with("//") {
                        continue;
                    }
                    // inside a string literal: after a quote
                    let Some(q) = code.find('"') else { continue };
                    let lit = code[q..].to_lowercase();
                    // spelt in pieces, so that this line does not match itself
                    for bad in [
                        concat!("ill", "-posed"),
                        concat!("ill", " posed"),
                        concat!("not", " converged"),
                        concat!("not", "-converged"),
                    ] {
                        if lit.contains(bad) {
                            found.push(format!("{}:{}: {bad}", p.display(), n + 1));
                        }
                    }
                }
            }
        }
        assert!(found.is_empty(), "{found:#?}");
    }
}
