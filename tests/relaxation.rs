//! Relaxation: estimator recovery, term-count choice, failure cases, presets,
//! conversions, the reader's bad-input corpus and the CLI.

use dea_fit::fit::relaxation::{self, Loading, Settings};
use dea_fit::io::relaxation::{from_table, log_times, RelaxationData, RelaxationOptions, Synthetic};
use dea_fit::io::table::Table;
use dea_fit::material::viscoelastic::Prony;
use std::path::Path;

fn data(s: &Synthetic) -> RelaxationData {
    let csv = s.csv(&["test data"]).unwrap();
    let t = Table::parse(Path::new("synthetic.csv"), csv.as_bytes()).unwrap();
    from_table(&t, &RelaxationOptions::default()).unwrap()
}

#[test]
fn scratch() {
    let prony = Prony::new(
        0.1951 * 222e3,
        &[(0.153, 0.478 * 222e3), (0.464, 0.205 * 222e3), (32.021, 0.0727 * 222e3), (215.85, 0.0492 * 222e3)],
    )
    .unwrap();
    let s = Synthetic {
        prony,
        strain: 0.5,
        ramp_time: None,
        times: log_times(0.01, 1000.0, 200, false),
        noise: 0.01,
        seed: 4910,
        record_strain: false,
    };
    let d = data(&s);
    for terms in [Some(4), None] {
        let set = Settings { terms, ..Settings::default() };
        let t0 = std::time::Instant::now();
        let f = relaxation::fit(&d, &Loading { strain: Some(0.5), ramp_time: None }, None, &set).unwrap();
        println!("{:?}", t0.elapsed());
        println!("{}", serde_json::to_string_pretty(&f.prony).unwrap());
        println!("{} {} {:?} {:?} {:?}", f.long_term_modulus_pa, f.rel_rmse, f.status, f.warnings, f.solver);
        if let Some(sel) = &f.selection { for c in &sel.candidates { println!("{} {:.4} {:?} {:.2} {:?} {:?}", c.terms, c.rel_rmse, c.aicc, c.delta, c.tau_s, c.note); } println!("{}", sel.reason); }
    }
}

#[test]
fn scratch_timing() {
    let prony = Prony::new(
        0.1951 * 222e3,
        &[(0.153, 0.478 * 222e3), (0.464, 0.205 * 222e3), (32.021, 0.0727 * 222e3), (215.85, 0.0492 * 222e3)],
    )
    .unwrap();
    let s = Synthetic { prony, strain: 0.5, ramp_time: None, times: log_times(0.01, 1000.0, 200, false), noise: 0.01, seed: 4910, record_strain: false };
    let d = data(&s);
    for method in [relaxation::Method::Grid, relaxation::Method::Refined] {
        for gpd in [10, 6, 5] {
            for (starts, ftol) in [(1, 1e-10), (4, 1e-10), (4, 1e-8), (4, 1e-6)] {
                let set = Settings { terms: Some(4), method, grid_per_decade: gpd, max_starts: starts, ftol, ..Settings::default() };
                let mut best = f64::INFINITY;
                let mut f = None;
                for _ in 0..20 {
                    let t0 = std::time::Instant::now();
                    f = Some(relaxation::fit(&d, &Loading { strain: Some(0.5), ramp_time: None }, None, &set).unwrap());
                    best = best.min(t0.elapsed().as_secs_f64());
                }
                let f = f.unwrap();
                let taus: Vec<f64> = f.prony.iter().map(|p| p.tau_s).collect();
                println!("{method:?} gpd {gpd} starts {starts} ftol {ftol}: {:.3} ms rel {:.5} it {} ev {} taus {:?}", best * 1e3, f.rel_rmse, f.solver.iterations, f.solver.evaluations, taus);
            }
        }
    }
}

#[test]
fn scratch_qp() {
    use nalgebra::{DMatrix, DVector};
    for cols in [31usize, 62] {
        let a = DMatrix::from_fn(200, cols, |i, j| (-(i as f64 * 0.05) / (0.01 * 1.2f64.powi(j as i32))).exp());
        let b = DVector::from_fn(200, |i, _| 1.0 + (-(i as f64) * 0.01).exp());
        let g = DMatrix::identity(cols, cols);
        let mut best = f64::INFINITY;
        let mut its = 0;
        for _ in 0..20 {
            let t0 = std::time::Instant::now();
            let s = dea_fit::fit::linear::constrained_least_squares(&a, &b, &g).unwrap();
            its = s.iterations;
            best = best.min(t0.elapsed().as_secs_f64());
        }
        let t0 = std::time::Instant::now();
        let p = a.transpose() * &a;
        println!("cols {cols}: {:.3} ms, {its} it, AtA {:?}", best * 1e3, t0.elapsed() + std::time::Duration::from_nanos(p.nrows() as u64));
    }
}
