//! `import`: a tracker's own export becomes a measurement CSV.

mod common;

use common::rk;
use robokrige::dataset::read_csv;
use std::path::Path;

const MAP: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/import/ipa-ur10.toml");

/// The original UR10 exports reproduce the shipped campaign files: every
/// joint, direction and covariate to their 6 printed decimals, every error to
/// within 0.005 mm (the errors need the tracker frame and the tool located by
/// least squares). Skips when the data is absent.
#[test]
fn the_original_ur10_exports_reproduce_the_shipped_campaigns() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/ipa-ur10");
    let cases = [
        (
            "Series_C/measurements_random_poses.csv",
            "series_c_random_poses.csv",
        ),
        (
            "Series_B/measurements_joint_configurations.csv",
            "series_b_joint_configurations.csv",
        ),
    ];
    if !root.join(cases[0].0).exists() {
        eprintln!("skipped: {} is absent", root.display());
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for (export, shipped) in cases {
        let out = dir.path().join("c.csv");
        let (c, stdout, err) = rk(&[
            "import",
            &root.join(export).display().to_string(),
            "--map-file",
            MAP,
            "--robot",
            "ur10",
            "-o",
            &out.display().to_string(),
        ]);
        assert_eq!(c, 0, "{err}");
        assert!(!err.contains("far beyond"), "{err}");
        assert!(
            stdout.contains("not imported") && stdout.contains("Timestamp"),
            "{stdout}"
        );
        let got = read_csv(&out).unwrap();
        let want = read_csv(&root.join(shipped)).unwrap();
        assert_eq!(got.len(), want.len());
        assert_eq!(got.dir, want.dir, "{export}: directions");
        let max = |f: &dyn Fn(usize) -> Vec<f64>, g: &dyn Fn(usize) -> Vec<f64>| {
            (0..got.len())
                .flat_map(|i| f(i).into_iter().zip(g(i)).map(|(a, b)| (a - b).abs()))
                .fold(0.0, f64::max)
        };
        let dq = max(&|i| got.q[i].clone(), &|i| want.q[i].clone());
        let (ge, we) = (got.errors.as_ref().unwrap(), want.errors.as_ref().unwrap());
        let de = max(&|i| ge[i].to_vec(), &|i| we[i].to_vec());
        let dt = max(&|i| vec![got.covariates[0].values[i]], &|i| {
            vec![want.covariate("temp_c").unwrap().values[i]]
        });
        assert!(dq <= 5.01e-7, "{export}: joints differ by {dq}°");
        assert!(de <= 0.005, "{export}: errors differ by {de} mm");
        assert!(dt <= 5.01e-7, "{export}: temperature differs by {dt}");
    }
}

/// Semicolons, decimal commas, radians and metres round-trip to degrees and
/// mm; positions stay positions without a robot.
#[test]
fn units_and_separators_convert_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let export = dir.path().join("export.txt");
    let mut text = String::from("stamp;J1;J2;X;Y;Z;T\n");
    let rows = [
        (0.5, -1.0, 1.25, 0.5, -0.25, 20.5),
        (0.25, -0.75, 1.5, 0.5, -0.25, 21.0),
    ];
    for (k, (a, b, x, y, z, t)) in rows.iter().enumerate() {
        text += &format!("{k};{a};{b};{x};{y};{z};{t}\n").replace('.', ",");
    }
    std::fs::write(&export, text).unwrap();
    let out = dir.path().join("c.csv");
    let (c, stdout, err) = rk(&[
        "import",
        &export.display().to_string(),
        "--angles",
        "rad",
        "--lengths",
        "m",
        "--map",
        "q1=J1,q2=J2,x=X,y=Y,z=Z,temp_c=T",
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(c, 0, "{err}");
    assert!(
        stdout.contains("not imported (no target names them): stamp"),
        "{stdout}"
    );
    let d = read_csv(&out).unwrap();
    assert!((d.q[1][0] - 0.25f64.to_degrees()).abs() < 1e-12);
    assert_eq!(d.positions.as_ref().unwrap()[0], [1250.0, 500.0, -250.0]);
    assert_eq!(d.dir[1], vec![-1.0, 1.0]);
    assert_eq!(d.covariate("T"), None);
    assert_eq!(d.covariate("temp_c").unwrap().values, vec![20.5, 21.0]);
    // a column the export lacks is named with what the export has
    let (c, _, err) = rk(&[
        "import",
        &export.display().to_string(),
        "--map",
        "q1=J1,q2=J9",
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(c, 1);
    assert!(
        err.contains("no column 'J9'") && err.contains("stamp, J1, J2"),
        "{err}"
    );
}

/// The same export with its radians read as degrees: imported (the frame
/// fit converges somewhere), but the errors' RMS of about 230 mm is said to
/// be implausible, with the radians named. Skips when the data is absent.
#[test]
fn an_export_read_in_the_wrong_angle_unit_is_said_to_be_implausible() {
    let export = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/ipa-ur10/Series_C/measurements_random_poses.csv");
    if !export.exists() {
        eprintln!("skipped: {} is absent", export.display());
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.csv");
    let (c, _, err) = rk(&[
        "import",
        &export.display().to_string(),
        "--map-file",
        MAP,
        "--robot",
        "ur10",
        "--angles",
        "deg",
        "-o",
        &out.display().to_string(),
    ]);
    assert_eq!(c, 0, "{err}");
    assert!(
        err.contains("far beyond a robot's absolute error") && err.contains("--angles rad"),
        "{err}"
    );
}
