//! The accuracy study: references, horizon, error falling with tolerance, the file.

use std::path::Path;

use studyrun::accuracy::{self, cheapest_within, describe};
use studyrun::output::StudyReader;
use studyrun::solve::Method;
use studyrun::study::Study;

/// A non-chaotic case (crank_rod, 600 rpm, 9 balls, no waviness; see tests/convergence.rs):
/// the two reference runs never part, DOPRI5's errors fall with its tolerance, RK4's
/// with its step, and the cheapest setting within 1 % is found and written.
#[test]
fn accuracy_study_of_a_non_chaotic_case() {
    let grid = "name: acc\nduration: 0.1\nsample_rate: 10000\ntransient: \"0.05 s\"\nlocation: crank_rod\nrpm: 600\neffects: [clearance, damping]\ngrid:\n  ball_count: [9]\n";
    let study = Study::from_yaml(grid, Path::new("acc.yaml")).unwrap();
    let ladder = [
        Method::DormandPrince {
            rtol: 1e-4,
            atol: 1e-8,
        },
        Method::DormandPrince {
            rtol: 1e-7,
            atol: 1e-11,
        },
        Method::DormandPrince {
            rtol: 1e-10,
            atol: 1e-14,
        },
        Method::Rk4 { step: 20e-6 },
        Method::Rk4 { step: 2.5e-6 },
    ];
    let (refs, ms) = accuracy::run(&study, &ladder).unwrap();
    assert_eq!(refs.len(), 1);
    assert_eq!(
        refs[0].horizon, 0.1,
        "a non-chaotic case keeps the whole run as its horizon"
    );
    assert!(
        refs[0].metric_uncertainty.iter().all(|u| *u < 1e-4),
        "{:?}",
        refs[0].metric_uncertainty
    );
    let err = |k: usize| ms[k].max_error[0];
    for m in &ms {
        println!(
            "{:?}: max err {:.1e}, metric err {:.1e}, {} RHS",
            describe(&m.method),
            m.max_error[0],
            m.metric_error[0],
            m.rhs_evals
        );
        assert!(m.error.is_none());
    }
    assert!(
        err(0) > err(1) && err(1) > err(2),
        "DOPRI5 error must fall with tolerance"
    );
    assert!(err(0) / err(2) > 1e3);
    assert!(err(3) > err(4), "RK4 error must fall with the step");
    assert!(ms[2].rhs_evals > ms[0].rhs_evals, "tighter costs more");
    let (best, judged) =
        cheapest_within(&ms, &refs, &ladder, 0.01, 0.1).expect("a setting within 1 %");
    assert_eq!(judged, 1);
    assert!(ms
        .iter()
        .find(|m| m.method == best)
        .unwrap()
        .metric_error
        .iter()
        .all(|e| *e < 0.01));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("acc.h5");
    accuracy::write_file(&path, &study, &refs, &ms).unwrap();
    let r = StudyReader::open(&path).unwrap();
    assert_eq!(r.layout().case_ids.len(), ladder.len());
    let names: Vec<&str> = r.layout().metrics.iter().map(|m| m.name.as_str()).collect();
    assert!(names.contains(&"metric_error_slider_acceleration") && names.contains(&"rhs_evals"));
    assert_eq!(r.read_case(2).unwrap().metrics[0], ms[2].max_error[0]);
}
