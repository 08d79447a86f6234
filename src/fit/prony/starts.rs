//! Stage 2: the starts of each term count's search, from the grid spectrum's peaks.

use super::grid::Grid;

/// A peak of the grid spectrum: total scaled modulus and its weighted mean ln τ.
#[derive(Debug, Clone, Copy)]
struct Peak {
    e: f64,
    ln_tau: f64,
}

fn merge(a: Peak, b: Peak) -> Peak {
    let e = a.e + b.e;
    Peak {
        e,
        ln_tau: if e > 0.0 {
            (a.e * a.ln_tau + b.e * b.ln_tau) / e
        } else {
            0.5 * (a.ln_tau + b.ln_tau)
        },
    }
}

/// Bring a sorted list of peaks to exactly `n`: merge the closest adjacent pair in ln τ
/// (`closest`) or fold the smallest peak into its nearer neighbour; split the largest
/// into two a factor 3 apart while too few.
fn reshape(mut peaks: Vec<Peak>, n: usize, closest: bool, window: (f64, f64)) -> Vec<Peak> {
    if n == 0 {
        return Vec::new();
    }
    if peaks.is_empty() && n > 0 {
        peaks.push(Peak {
            e: 1.0,
            ln_tau: 0.5 * (window.0 + window.1),
        });
    }
    while peaks.len() > n {
        let i = if closest {
            (0..peaks.len() - 1)
                .min_by(|&a, &b| {
                    (peaks[a + 1].ln_tau - peaks[a].ln_tau)
                        .total_cmp(&(peaks[b + 1].ln_tau - peaks[b].ln_tau))
                })
                .expect("two peaks")
        } else {
            let j = (0..peaks.len())
                .min_by(|&a, &b| peaks[a].e.total_cmp(&peaks[b].e))
                .expect("a peak");
            if j == 0 {
                0
            } else if j == peaks.len() - 1
                || peaks[j].ln_tau - peaks[j - 1].ln_tau < peaks[j + 1].ln_tau - peaks[j].ln_tau
            {
                j - 1
            } else {
                j
            }
        };
        let m = merge(peaks[i], peaks[i + 1]);
        peaks[i] = m;
        peaks.remove(i + 1);
    }
    while peaks.len() < n {
        let j = (0..peaks.len())
            .max_by(|&a, &b| peaks[a].e.total_cmp(&peaks[b].e))
            .expect("a peak");
        let p = peaks[j];
        let d = 0.5 * 3f64.ln();
        peaks[j] = Peak {
            e: 0.5 * p.e,
            ln_tau: p.ln_tau - d,
        };
        peaks.insert(
            j + 1,
            Peak {
                e: 0.5 * p.e,
                ln_tau: p.ln_tau + d,
            },
        );
    }
    peaks
}

/// Peaks of the grid spectrum: runs of consecutive non-zero grid moduli.
fn peaks(taus: &[f64], c: &[f64]) -> Vec<Peak> {
    let total: f64 = c[1..].iter().sum();
    // An interior-point solution is never exactly zero: 1 % of the largest grid
    // modulus separates the spectrum from the solver's residue.
    let thr = 1e-2 * c[1..].iter().copied().fold(0.0, f64::max);
    let mut out: Vec<Peak> = Vec::new();
    let mut open = false;
    for (j, &e) in c[1..].iter().enumerate() {
        if e > thr {
            let p = Peak {
                e,
                ln_tau: taus[j].ln(),
            };
            match (open, out.last_mut()) {
                (true, Some(last)) => *last = merge(*last, p),
                _ => out.push(p),
            }
            open = true;
        } else {
            open = false;
        }
    }
    // Prune peaks below 0.1 % of the relaxing modulus: noise, not spectrum.
    out.retain(|p| p.e >= 1e-3 * total);
    out
}

/// The starts of a term count's search, as ln τ of each term: the grid spectrum's
/// peaks brought to N by merging the closest pair, then by folding the smallest peak
/// ([`reshape`]), N terms spread evenly over the window, and the first start's terms
/// pushed half a grid step apart (breaks ties between close modes); the distinct
/// ones, at most `max`.
pub fn starts(window: (f64, f64), grid: &Grid, n: usize, max: usize) -> Vec<Vec<f64>> {
    let (taus, c, _) = grid;
    let pk = peaks(taus, c);
    let win = (window.0.ln(), window.1.ln());
    let ln_taus = |closest: bool| -> Vec<f64> {
        reshape(pk.clone(), n, closest, win)
            .iter()
            .map(|q| q.ln_tau)
            .collect()
    };
    let mut starts = vec![ln_taus(true), ln_taus(false)];
    if n > 0 {
        starts.push(
            (0..n)
                .map(|i| win.0 + (win.1 - win.0) * (i as f64 + 0.5) / n as f64)
                .collect(),
        );
        let mut wide = ln_taus(true);
        for (i, l) in wide.iter_mut().enumerate() {
            *l += if i % 2 == 0 { -0.35 } else { 0.35 };
        }
        starts.push(wide);
    }
    starts.dedup_by(|a, b| a.iter().zip(b.iter()).all(|(x, y)| (x - y).abs() < 1e-9));
    starts.truncate(max);
    starts
}
