//! File patterns of the project file: `*` (any run of characters but `/`) and `?`
//! (one character) in any path component, e.g. `raw/vhb*/tensile_*.csv`. A pattern
//! is relative to the project folder; its matches are files, in sorted order, so
//! that a new file is picked up and the argument list is the same on every machine.
//! A component starting with `.` is matched only by a pattern component that does.

use std::path::Path;

/// Whether `s` holds a pattern character.
pub fn is_pattern(s: &str) -> bool {
    s.contains(['*', '?'])
}

/// The files (relative to `dir`, `/`-separated) that `pattern` matches, sorted.
pub fn expand(dir: &Path, pattern: &str) -> Vec<String> {
    let parts: Vec<&str> = pattern.split('/').filter(|p| !p.is_empty()).collect();
    let mut found = Vec::new();
    walk(dir, "", &parts, &mut found);
    found.sort();
    found
}

fn walk(dir: &Path, prefix: &str, parts: &[&str], found: &mut Vec<String>) {
    let Some((first, rest)) = parts.split_first() else {
        return;
    };
    let join = |name: &str| match prefix {
        "" => name.to_string(),
        p => format!("{p}/{name}"),
    };
    let names: Vec<String> = if is_pattern(first) {
        let Ok(rd) = std::fs::read_dir(dir.join(prefix)) else {
            return;
        };
        rd.filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| (first.starts_with('.') || !n.starts_with('.')) && matches(first, n))
            .collect()
    } else {
        vec![first.to_string()]
    };
    for n in names {
        let p = join(&n);
        if rest.is_empty() {
            if dir.join(&p).is_file() {
                found.push(p);
            }
        } else if dir.join(&p).is_dir() {
            walk(dir, &p, rest, found);
        }
    }
}

/// Whether `name` matches the component pattern `pat` (`*` any run, `?` one
/// character), by the usual backtracking over the last `*`.
pub fn matches(pat: &str, name: &str) -> bool {
    let p: Vec<char> = pat.chars().collect();
    let n: Vec<char> = name.chars().collect();
    let (mut i, mut j) = (0, 0);
    let mut star: Option<(usize, usize)> = None;
    while j < n.len() {
        if i < p.len() && (p[i] == '?' || p[i] == n[j]) {
            i += 1;
            j += 1;
        } else if i < p.len() && p[i] == '*' {
            star = Some((i, j));
            i += 1;
        } else if let Some((si, sj)) = star {
            i = si + 1;
            j = sj + 1;
            star = Some((si, sj + 1));
        } else {
            return false;
        }
    }
    p[i..].iter().all(|&c| c == '*')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stars_and_marks() {
        assert!(matches("tensile_*.csv", "tensile_01.csv"));
        assert!(matches("tensile_*.csv", "tensile_.csv"));
        assert!(!matches("tensile_*.csv", "tensile_01.csvx"));
        assert!(matches("s?0*", "s10_cpd.csv"));
        assert!(!matches("s?0*", "s1_cpd.csv"));
        assert!(matches("*", "x"));
        assert!(matches("a*b*c", "aXbYbZc"));
    }

    #[test]
    fn expands_sorted_across_folders() {
        let d = tempfile::tempdir().unwrap();
        for f in [
            "raw/b/t_2.csv",
            "raw/a/t_1.csv",
            "raw/a/t_0.csv",
            "raw/a/x.txt",
        ] {
            let p = d.path().join(f);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, "").unwrap();
        }
        assert_eq!(
            expand(d.path(), "raw/*/t_*.csv"),
            ["raw/a/t_0.csv", "raw/a/t_1.csv", "raw/b/t_2.csv"]
        );
        assert!(expand(d.path(), "raw/c/*.csv").is_empty());
    }
}
