//! Whether a shard can merge with the first: the same variables and coordinates,
//! matched by name, and where the first shard's variables are in it.

use super::super::{Layout, Param, VarSpec};

/// What differs between the variables `a` of a shard and `b` of the first (matched by
/// name, in any order: ncks sorts them by name): a variable one of them lacks, or one
/// whose units or long name differ; `None` when they are alike.
pub(super) fn variables_difference<'a>(
    a: impl IntoIterator<Item = &'a VarSpec>,
    b: impl IntoIterator<Item = &'a VarSpec>,
) -> Option<String> {
    let a: Vec<&VarSpec> = a.into_iter().collect();
    let b: Vec<&VarSpec> = b.into_iter().collect();
    let find = |specs: &[&'a VarSpec], name: &str| specs.iter().find(|s| s.name == name).copied();
    for x in &a {
        match find(&b, &x.name) {
            None => return Some(format!("it has a variable `{}`", x.name)),
            Some(y) if y.units != x.units => {
                return Some(format!(
                    "its `{}` has the units `{}`, not `{}`",
                    x.name, x.units, y.units
                ))
            }
            Some(y) if y.long_name != x.long_name => {
                return Some(format!("its `{}` has another long_name", x.name))
            }
            Some(_) => {}
        }
    }
    b.iter()
        .find(|y| find(&a, &y.name).is_none())
        .map(|y| format!("it has no variable `{}`", y.name))
}

/// What keeps the shard of layout `l` from merging with the first shard's `first`, in
/// words; `None` when nothing does.
pub(super) fn layout_difference(l: &Layout, first: &Layout) -> Option<String> {
    fn params(l: &Layout) -> impl Iterator<Item = &VarSpec> {
        l.parameters.iter().map(|p| &p.spec)
    }
    let coordinates = [
        ("time", l.times != first.times),
        ("frequency", l.frequencies != first.frequencies),
        ("replicate", l.replicates != first.replicates),
        ("revolution", l.revolutions != first.revolutions),
        ("order", l.orders != first.orders),
        ("sk_frequency", l.sk_frequencies != first.sk_frequencies),
    ];
    if let Some((name, _)) = coordinates.iter().find(|(_, differs)| *differs) {
        return Some(format!("its `{name}` coordinate differs"));
    }
    variables_difference(&l.series, &first.series)
        .or_else(|| variables_difference(&l.spectra, &first.spectra))
        .or_else(|| variables_difference(&l.kurtosis, &first.kurtosis))
        .or_else(|| variables_difference(&l.metrics, &first.metrics))
        .or_else(|| variables_difference(&l.replicate_metrics, &first.replicate_metrics))
        .or_else(|| variables_difference(&l.revolution_metrics, &first.revolution_metrics))
        .or_else(|| variables_difference(&l.order_spectra, &first.order_spectra))
        .or_else(|| variables_difference(params(l), params(first)))
        .or_else(|| {
            let refs = |l: &'_ Layout| {
                l.reference_parameters
                    .iter()
                    .map(|p| p.spec.clone())
                    .collect::<Vec<_>>()
            };
            variables_difference(&refs(l), &refs(first))
        })
        .or_else(|| variables_difference(&l.reference_series, &first.reference_series))
}

/// For each variable of `want`, its index in `have` (same names, checked before).
pub(super) fn positions(want: &[VarSpec], have: &[VarSpec]) -> Vec<usize> {
    want.iter()
        .map(|w| {
            have.iter()
                .position(|h| h.name == w.name)
                .expect("same variables")
        })
        .collect()
}

/// Where each of the first shard's variables is in a shard.
pub(super) struct Order {
    pub(super) series: Vec<usize>,
    pub(super) spectra: Vec<usize>,
    pub(super) metrics: Vec<usize>,
    pub(super) replicate_metrics: Vec<usize>,
    pub(super) revolution_metrics: Vec<usize>,
    pub(super) order_spectra: Vec<usize>,
    pub(super) parameters: Vec<usize>,
    pub(super) reference_parameters: Vec<usize>,
    pub(super) reference_series: Vec<usize>,
}

impl Order {
    /// Where each variable of the first shard's `first` is in the shard of layout `l`.
    pub(super) fn of(l: &Layout, first: &Layout) -> Self {
        let specs = |ps: &[Param]| ps.iter().map(|p| p.spec.clone()).collect();
        let (want, have): (Vec<VarSpec>, Vec<VarSpec>) =
            (specs(&first.parameters), specs(&l.parameters));
        let (want_refs, have_refs): (Vec<VarSpec>, Vec<VarSpec>) = (
            specs(&first.reference_parameters),
            specs(&l.reference_parameters),
        );
        Order {
            series: positions(&first.series, &l.series),
            spectra: positions(&first.spectra, &l.spectra)
                .into_iter()
                .chain(
                    positions(&first.kurtosis, &l.kurtosis)
                        .into_iter()
                        .map(|i| l.spectra.len() + i),
                )
                .collect(),
            metrics: positions(&first.metrics, &l.metrics),
            replicate_metrics: positions(&first.replicate_metrics, &l.replicate_metrics),
            revolution_metrics: positions(&first.revolution_metrics, &l.revolution_metrics),
            order_spectra: positions(&first.order_spectra, &l.order_spectra),
            parameters: positions(&want, &have),
            reference_parameters: positions(&want_refs, &have_refs),
            reference_series: positions(&first.reference_series, &l.reference_series),
        }
    }
}
