//! The shipped datasets: transcriptions agree with the reference copies, and the
//! synthetic files are what their stated generator produces.

use dea_fit::io::tensile::{read, TensileOptions};
use dea_fit::material::hyperelastic::{Mode, ModelSpec, OgdenForm};
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
#[cfg_attr(
    not(shared_datasets),
    ignore = "needs the shared reference copy ../shared/datasets (see build.rs)"
)]
fn treloar_transcription_matches_the_reference_copy() {
    let shared = root().join("../shared/datasets/treloar");
    for (ours, theirs, mode) in [
        ("uniaxial", "uniaxial", Mode::Uniaxial),
        ("equibiaxial", "equibiaxial", Mode::Equibiaxial),
        ("planar", "pure_shear", Mode::Planar),
    ] {
        let opts = TensileOptions {
            mode: Some(mode),
            ..Default::default()
        };
        let a = read(&root().join(format!("datasets/treloar/{ours}.csv")), &opts).unwrap();
        let b = read(&shared.join(format!("{theirs}.csv")), &opts).unwrap();
        assert_eq!(a.samples.len(), b.samples.len(), "{ours}");
        for (x, y) in a.samples.iter().zip(&b.samples) {
            // A transcription must reproduce every printed digit.
            assert_eq!(
                (x.stretch, x.stress, x.mode),
                (y.stretch, y.stress, y.mode),
                "{ours}"
            );
        }
    }
}

#[test]
fn synthetic_vhb_data_scatter_about_their_generating_model() {
    // Seed Table 3.2 Yeoh constants; noise 1 % + 0.5 kPa: every point lies within
    // 5 standard deviations of the clean curve, and the noise is really there.
    let model = ModelSpec::new("yeoh", OgdenForm::Abaqus).build().unwrap();
    let p = [0.0693e6, -8.88e-4 * 1e6, 16.7e-6 * 1e6];
    for (file, mode) in [
        ("uniaxial", Mode::Uniaxial),
        ("equibiaxial", Mode::Equibiaxial),
        ("planar", Mode::Planar),
    ] {
        let d = read(
            &root().join(format!("datasets/vhb4910/{file}.csv")),
            &TensileOptions::default(),
        )
        .unwrap();
        assert!(
            d.samples.iter().all(|s| s.mode == mode),
            "{file}: the file's # mode comment"
        );
        let mut any_noise = false;
        for s in &d.samples {
            let clean = model.nominal_stress(&p, mode, s.stretch);
            let sigma = (0.01 * clean).hypot(500.0);
            assert!(
                (s.stress - clean).abs() <= 5.0 * sigma,
                "{file} λ={}",
                s.stretch
            );
            any_noise |= (s.stress - clean).abs() > 1.0;
        }
        assert!(any_noise);
    }
}

/// Reference files copied into `datasets/` are the bytes their SOURCE notes name
/// (sha256 as stated there).
#[test]
fn copied_reference_files_match_their_source_checksums() {
    for (file, sha) in [
        (
            "lcr_samples/E4990A-example1.csv",
            "38c24a0227609ce8e35a16ae6d8aef02c0fe1b20038a11c06be80816225d7e1a",
        ),
        (
            "lcr_samples/E4990A-example2.csv",
            "db48e3c7aacea456522b93d3eb8ac751a20e90b365c18454b68a1a34f735b824",
        ),
        (
            "composites/mixing_rule_check_seed.csv",
            "1f8b0dd43042d3543a8910482c0a411eefa84b8de9234be4383db6acc9a6f6e8",
        ),
    ] {
        let path = root().join("datasets").join(file);
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(dea_fit::io::sha256_hex(&bytes), sha, "{file}");
        let notes = [
            "datasets/lcr_samples/SOURCE.md",
            "datasets/composites/README.md",
        ]
        .map(|n| std::fs::read_to_string(root().join(n)).expect("SOURCE note"));
        assert!(
            notes.iter().any(|n| n.contains(sha)),
            "{file}: its checksum is in no SOURCE note"
        );
    }
}
