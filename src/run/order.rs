//! The order in which the workers take a run's cases.
//!
//! Workers take cases one at a time from one shared list, so a run ends when the last
//! case started ends: a long case started last leaves the other workers idle for most
//! of its length. The list therefore starts with the cases expected to cost most
//! (longest processing time first), which leaves cheap ones to fill the end. The
//! expectation is a guess from the parameters, used for nothing but this order: a
//! wrong guess costs idle time at the end, never a different result (each case is
//! simulated on its own, and rows are written where they belong).

use crate::study::Study;

/// Orders `pending` (positions in `rows`, which index `study.cases`) for the workers:
/// the most crank revolutions first, by the shortest first revolution (every case of a
/// study simulates the same time,
/// and contacts, load-zone passes and waviness passes come per revolution, so the
/// integrator's steps grow with the speed), ties in reverse grid order. The tie rule
/// assumes what is usual, not required: that a grid lists its values in ascending
/// order, so that its costly cases (higher speed, larger waviness amplitude, more
/// balls; the bearing at crank_rod, listed after crank_ground) tend to come last.
pub(super) fn dispatch_order(study: &Study, rows: &[usize], pending: &mut [usize]) {
    let revolution = |position: usize| study.cases[rows[position]].params.revolution_time();
    pending.sort_by(|&a, &b| revolution(a).total_cmp(&revolution(b)).then(b.cmp(&a)));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A study of `rpms` (one case each, in this grid order).
    fn study_of(rpms: &[f64]) -> Study {
        let values: Vec<String> = rpms.iter().map(f64::to_string).collect();
        let text = format!(
            "name: order\nduration: 0.01\nsample_rate: 1000\ngrid:\n  rpm: [{}]\n  damping: [300, 400]\n",
            values.join(", ")
        );
        Study::from_yaml(&text, std::path::Path::new("order.yaml")).expect("valid grid")
    }

    #[test]
    fn fastest_cases_first_ties_in_reverse_grid_order() {
        let study = study_of(&[300.0, 900.0, 600.0]);
        let rows: Vec<usize> = (0..study.cases.len()).collect();
        let mut pending = rows.clone();
        dispatch_order(&study, &rows, &mut pending);
        let rpm: Vec<f64> = pending
            .iter()
            .map(|&p| study.cases[rows[p]].params.rpm)
            .collect();
        assert_eq!(rpm, [900.0, 900.0, 600.0, 600.0, 300.0, 300.0]);
        for pair in pending.chunks(2) {
            assert!(pair[0] > pair[1], "ties in reverse grid order: {pending:?}");
        }
    }

    #[test]
    fn a_shard_or_a_resumed_run_orders_only_its_pending_positions() {
        let study = study_of(&[300.0, 900.0, 600.0]);
        // A shard's rows, and a resumed run where positions 0 and 2 are done.
        let rows = vec![1, 2, 4, 5];
        let mut pending = vec![1, 3];
        dispatch_order(&study, &rows, &mut pending);
        assert_eq!(pending, [1, 3], "900 rpm (row 2) before 600 rpm (row 5)");
        let mut pending = vec![3, 1, 0];
        dispatch_order(&study, &rows, &mut pending);
        assert_eq!(pending, [1, 3, 0]);
    }
}
