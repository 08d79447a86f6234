//! The dependency graph of a project's steps: the order they run in, the cycle
//! that prevents one, and the steps a selection of targets needs.

use crate::error::{Error, Result};
use crate::project::file::{near, Project};
use crate::project::glob::matches;

/// The steps in an order where each comes after every step it needs (Kahn's
/// algorithm; among the steps ready together, the project file's order), or the
/// error naming a cycle's members.
pub fn order(p: &Project) -> Result<Vec<usize>> {
    let n = p.steps.len();
    let mut waiting: Vec<usize> = p.steps.iter().map(|s| s.needs.len()).collect();
    let mut users: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (i, s) in p.steps.iter().enumerate() {
        for &j in &s.needs {
            users[j].push(i);
        }
    }
    let mut ready: std::collections::BTreeSet<usize> =
        (0..n).filter(|&i| waiting[i] == 0).collect();
    let mut out = Vec::with_capacity(n);
    while let Some(i) = ready.pop_first() {
        out.push(i);
        for &u in &users[i] {
            waiting[u] -= 1;
            if waiting[u] == 0 {
                ready.insert(u);
            }
        }
    }
    if out.len() == n {
        return Ok(out);
    }
    // a step left waiting is on a cycle or after one: walk back through the
    // unfinished steps it needs until one repeats
    let left: Vec<bool> = waiting.iter().map(|&w| w > 0).collect();
    let mut path = vec![(0..n).find(|&i| left[i]).expect("a step is left")];
    loop {
        let last = *path.last().expect("non-empty");
        let next = p.steps[last]
            .needs
            .iter()
            .copied()
            .find(|&j| left[j])
            .expect("a waiting step needs a waiting step");
        if let Some(k) = path.iter().position(|&x| x == next) {
            let cycle: Vec<usize> = path[k..].to_vec();
            let mut names: Vec<&str> = cycle.iter().map(|&i| p.steps[i].target.as_str()).collect();
            names.push(names[0]);
            return Err(Error::input(
                p.steps[cycle[0]].at.clone(),
                format!(
                    "the steps form a cycle: {} (each reads the next one's output)",
                    names.join(" → ")
                ),
            )
            .with_hint("a step cannot read, directly or through others, what it writes itself: remove one of these target references (docs/project.md)"));
        }
        path.push(next);
    }
}

/// The steps `patterns` select with every step they need, as a mask; no pattern
/// selects every step. A pattern is a target (`vhb4910/tensile`), a target
/// pattern (`vhb4910/*`, `*/tensile`) or a pattern of an output path
/// (`fits/vhb4910-*`); one that selects nothing is refused.
pub fn select(p: &Project, patterns: &[String]) -> Result<Vec<bool>> {
    let mut chosen = matched(p, patterns)?;
    // with what they need
    let mut stack: Vec<usize> = (0..chosen.len()).filter(|&i| chosen[i]).collect();
    while let Some(i) = stack.pop() {
        for &j in &p.steps[i].needs {
            if !chosen[j] {
                chosen[j] = true;
                stack.push(j);
            }
        }
    }
    Ok(chosen)
}

/// The steps `patterns` select ([`select`]), without the steps they need.
pub fn matched(p: &Project, patterns: &[String]) -> Result<Vec<bool>> {
    let n = p.steps.len();
    if patterns.is_empty() {
        return Ok(vec![true; n]);
    }
    let mut chosen = vec![false; n];
    for pat in patterns {
        let pat = pat.trim_start_matches("./");
        let mut any = false;
        for (i, s) in p.steps.iter().enumerate() {
            if matches(pat, &s.target) || s.outputs.iter().any(|o| matches(pat, o)) {
                chosen[i] = true;
                any = true;
            }
        }
        if !any {
            let targets: Vec<&str> = p.steps.iter().map(|s| s.target.as_str()).collect();
            return Err(
                Error::settings(format!("no target of the project matches '{pat}'")).with_hint(
                    format!("{}targets: {}", near(pat, &targets), targets.join(", ")),
                ),
            );
        }
    }
    Ok(chosen)
}
