//! Physics-based models (seeds 000, 002): identification from simulated
//! indexing tests recovers the simulator's truth within the noise.

use robokrige::dataset::read_csv;
use robokrige::kinematics;
use robokrige::physics::{Geometry, ScaraOptions, identify_scara};
use robokrige::sim::campaign::simulate_on;
use robokrige::sim::{
    CampaignKind, CampaignSpec, ErrorProfile, ScaraTruth, SimOutput, TrueRobot, Truth,
};
use std::path::{Path, PathBuf};

fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("datasets")
        .join(name)
}

fn truth(name: &str) -> Truth {
    serde_json::from_str(&std::fs::read_to_string(shipped(name)).unwrap()).unwrap()
}

/// Identification errors (identified − truth) on the indexing campaign of
/// the true robot `seed`: ΔL1, ΔL2 (mm), θ20 (deg), APD rms J1, J2 (deg).
fn scara_errors(seed: u64, noise: bool) -> [f64; 5] {
    let nominal = kinematics::preset("scara-rh3frh5515").unwrap();
    let profile = ErrorProfile::for_robot(&nominal);
    let mut robot = TrueRobot::draw(&nominal, &profile, seed);
    if !noise {
        robot.noise.repeatability_sigma_deg = 0.0;
        robot.noise.tracker_mpe_const_mm = 0.0;
        robot.noise.tracker_mpe_per_m_mm = 0.0;
    }
    let spec = CampaignSpec::new(CampaignKind::Indexing, seed);
    let (SimOutput::Measurements(data), _) = simulate_on(&robot, &spec).unwrap() else {
        panic!("indexing gives measurements")
    };
    let id = identify_scara(&data, &nominal, &ScaraOptions::default()).unwrap();
    let Geometry::Scara(g) = &id.model.geometry else {
        panic!("not a SCARA geometry")
    };
    let tr = ScaraTruth::of(&robot, &g.rest);
    let mut out = [
        g.dl1_mm - tr.dl1_mm,
        g.dl2_mm - tr.dl2_mm,
        g.theta20_deg - tr.theta20_deg,
        0.0,
        0.0,
    ];
    for j in 0..2 {
        let tab = id.model.apd[j].as_ref().unwrap();
        let mut sq = 0.0;
        for (i, a) in tab.angles_deg.iter().enumerate() {
            for (d, v) in [(1.0, tab.plus[i]), (-1.0, tab.minus[i])] {
                sq += (v - ScaraTruth::apd(&robot, j, g.rest[j], *a, d)).powi(2);
            }
        }
        out[3 + j] = (sq / (2 * tab.angles_deg.len()) as f64).sqrt();
    }
    out
}

#[test]
fn scara_identification_is_exact_without_noise() {
    for seed in [1, 2, 3] {
        let e = scara_errors(seed, false);
        assert!(e[0].abs() < 1e-6 && e[1].abs() < 1e-6, "seed {seed}: {e:?}");
        assert!(e[2].abs() < 1e-5, "seed {seed}: {e:?}");
        assert!(e[3] < 1e-6 && e[4] < 1e-6, "seed {seed}: {e:?}");
    }
}

#[test]
fn scara_identification_recovers_the_truth_within_the_noise() {
    let mut worst = [0.0_f64; 5];
    for seed in 1..=20 {
        let e = scara_errors(seed, true);
        eprintln!("seed {seed}: {e:?}");
        for k in 0..5 {
            worst[k] = worst[k].max(e[k].abs());
        }
    }
    eprintln!("worst: {worst:?}");
}
