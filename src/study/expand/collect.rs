//! The expanded cases, collected one at a time: those of the study (or of one shard
//! of it) kept with the ideal references they use, and what the study's checks and
//! file need of every case folded as it passes. A shard thus holds its own cases, and
//! every figure of the whole study (case and reference ids, revolutions, transient,
//! the refusals) is the one the whole study's expansion finds.

use std::collections::HashSet;

use super::references::{reference_key, reference_of, BodyKey};
use super::*;
use crate::mechanism::CrankDrive;
use crate::study::{Reference, Shard, WholeStudy};

/// Which joints the cases at a location have.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Joints {
    /// Some case is at a location (not `ideal`).
    pub located: bool,
    /// Some case at a location has a ball bearing.
    pub ball: bool,
    /// Some case at a location has a plain journal.
    pub plain: bool,
}

/// The cases collected so far.
pub(super) struct Collected {
    /// The shard whose cases are kept; none: every case.
    part: Option<Shard>,
    /// Whether each case's replicate perturbation bound is folded (`replicates:`).
    replicates: bool,
    /// The kept cases, in id order.
    cases: Vec<Case>,
    /// The references of the kept cases, in the order of their first kept case.
    references: Vec<Reference>,
    /// The ids of [`Collected::references`].
    held: HashSet<usize>,
    /// The index of each distinct [`BodyKey`] (body set, speed profile, gravity).
    bodies: HashMap<BodyKey, u32>,
    /// The speed profile of each body index.
    profiles: Vec<Option<SpeedProfile>>,
    /// Each distinct reference, (body index, rpm bits), with its id and first case.
    speeds: HashMap<(u32, u64), (usize, u64)>,
    /// The joints of the study's cases.
    pub joints: Joints,
    /// The longest first crank revolution of any case (s).
    pub longest_revolution: f64,
    /// The first case with a noise realisation other than 0: its id and realisation.
    pub realization: Option<(u64, u64)>,
    /// The case whose replicate perturbation bound is smallest, with the bound (m)
    /// and what it is 1 % of; folded only for a study with `replicates:`.
    pub tightest: Option<(u64, (f64, String))>,
    /// The whole study's figures (its reference count set at the end).
    whole: WholeStudy,
}

impl Collected {
    /// Nothing collected yet, of a study of `total` cases of which `part`'s are
    /// kept; `replicates`: fold the replicate perturbation bounds.
    pub(super) fn new(part: Option<Shard>, total: u64, replicates: bool) -> Self {
        let kept = part.map_or(total, |s| shard_size(total, s));
        Self {
            part,
            replicates,
            cases: Vec::with_capacity(kept as usize),
            references: Vec::new(),
            held: HashSet::new(),
            bodies: HashMap::new(),
            profiles: Vec::new(),
            speeds: HashMap::new(),
            joints: Joints::default(),
            longest_revolution: 0.0,
            realization: None,
            tightest: None,
            whole: WholeStudy::default(),
        }
    }

    /// The id the next case collected takes.
    pub(super) fn next_id(&self) -> u64 {
        self.whole.cases
    }

    /// Collects `case` (whose id is [`Collected::next_id`]): numbers its reference,
    /// folds it into the study's figures and keeps it when it is the part's.
    pub(super) fn push(&mut self, mut case: Case) {
        debug_assert_eq!(case.id, self.whole.cases);
        self.whole.add(&case.params);
        let p = &case.params;
        let located = p.location != Site::Ideal;
        self.joints.located |= located;
        self.joints.ball |= located && !p.joint.is_plain();
        self.joints.plain |= located && p.joint.is_plain();
        self.longest_revolution = self.longest_revolution.max(p.revolution_time());
        if p.noise_realization != 0 && self.realization.is_none() {
            self.realization = Some((case.id, p.noise_realization));
        }
        if self.replicates {
            self.fold_perturbation_bound(&case);
        }
        case.reference = self.reference_id(&case);
        if self.part.is_none_or(|s| case.id % s.n == s.k - 1) {
            if self.held.insert(case.reference) {
                self.references.push(Reference {
                    id: case.reference,
                    params: reference_of(&case.params),
                });
            }
            self.cases.push(case);
        }
    }

    /// Keeps the smaller of the tightest perturbation bound so far and `case`'s (the
    /// first case of the smallest).
    fn fold_perturbation_bound(&mut self, case: &Case) {
        if let Some(bound) = super::replicates::perturbation_bound(&case.params) {
            if self
                .tightest
                .as_ref()
                .is_none_or(|(_, t)| bound.0.total_cmp(&t.0).is_lt())
            {
                self.tightest = Some((case.id, bound));
            }
        }
    }

    /// The id of `case`'s reference: its index among the distinct references in the
    /// order of their first case, a new one when no earlier case has it.
    fn reference_id(&mut self, case: &Case) -> usize {
        let (body, rpm) = reference_key(&case.params);
        let next_body = self.profiles.len() as u32;
        let body = *self.bodies.entry(body).or_insert_with(|| {
            self.profiles.push(case.params.speed.clone());
            next_body
        });
        let next = self.speeds.len();
        self.speeds.entry((body, rpm)).or_insert((next, case.id)).0
    }

    /// The crank drive of the distinct speed (`body`, `rpm` bits): its case's
    /// [`CaseParams::drive`].
    fn drive(&self, body: u32, rpm: u64) -> CrankDrive {
        match &self.profiles[body as usize] {
            None => CrankDrive::constant(f64::from_bits(rpm)),
            Some(profile) => profile.drive(),
        }
    }

    /// The crank drive of every distinct speed, with the first case that runs it.
    fn drives(&self) -> impl Iterator<Item = (u64, CrankDrive)> + '_ {
        self.speeds
            .iter()
            .map(|(&(body, rpm), &(_, first))| (first, self.drive(body, rpm)))
    }

    /// The most whole revolutions of any case between `transient` and `duration` (s).
    pub(super) fn most_revolutions(&self, transient: f64, duration: f64) -> usize {
        self.drives()
            .map(|(_, d)| revolution_count(&d, transient, duration))
            .max()
            .unwrap_or(0)
    }

    /// The fewest whole revolutions of any case between `first` and `last` (s), with
    /// the first case that turns so few ([`fewest_whole_revolutions`]).
    pub(super) fn fewest_whole_revolutions(&self, first: f64, last: f64) -> Option<(usize, u64)> {
        fewest_whole_revolutions(self.drives(), first, last)
    }

    /// The distinct references of the whole study numbered so far.
    pub(super) fn study_references(&self) -> u64 {
        self.speeds.len() as u64
    }

    /// The kept references (in id order), the kept cases and the whole study's
    /// figures.
    pub(super) fn finish(mut self) -> (Vec<Case>, Vec<Reference>, WholeStudy) {
        self.references.sort_unstable_by_key(|r| r.id);
        self.whole.references = self.study_references();
        (self.cases, self.references, self.whole)
    }
}

/// The cases of `part` among `total`: the ids below `total` ≡ k − 1 (mod n).
pub(super) fn shard_size(total: u64, part: Shard) -> u64 {
    total / part.n + u64::from(total % part.n >= part.k)
}

/// The fewest whole revolutions between `first` and `last` (s) of the `drives` (each
/// with its case id), and the smallest id of those that turn so few; none without
/// drives.
pub(super) fn fewest_whole_revolutions(
    drives: impl Iterator<Item = (u64, CrankDrive)>,
    first: f64,
    last: f64,
) -> Option<(usize, u64)> {
    drives
        .map(|(id, d)| (whole_revolutions(&d, first, last), id))
        .min()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shard_sizes_count_the_ids_of_each_shard_and_add_up_to_the_study() {
        for total in [0u64, 1, 5, 12, 13, 1000] {
            for n in [1u64, 2, 3, 7, 20] {
                let sizes: Vec<u64> = (1..=n).map(|k| shard_size(total, Shard { k, n })).collect();
                for (k, &size) in (1..=n).zip(&sizes) {
                    let ids = (0..total).filter(|id| id % n == k - 1).count() as u64;
                    assert_eq!(size, ids, "{total} cases, shard {k}/{n}");
                }
                assert_eq!(sizes.iter().sum::<u64>(), total);
            }
        }
    }
}
