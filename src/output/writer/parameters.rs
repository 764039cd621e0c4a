//! Parameters written in blocks of rows: the `[case]` and `[reference]` parameter
//! variables of a file made by [`StudyWriter::create_unfilled`], so that whoever
//! writes them (a merge of many shards) never holds every row's values at once.

use super::*;

/// The parameter variables of a file created unfilled: for each parameter, then each
/// reference parameter, the rows written so far and the digest of a text
/// parameter's strings so far.
pub(super) struct Unfilled {
    /// Rows written, per parameter then per reference parameter.
    next: Vec<usize>,
    /// CRC-32 of a text parameter's strings so far ([`text::digest_continue`]), per
    /// parameter then per reference parameter (unused for numbers).
    crc: Vec<u32>,
}

impl Unfilled {
    /// Nothing written of `layout`'s parameters and reference parameters yet.
    pub(super) fn new(layout: &Layout) -> Self {
        let n = layout.parameters.len() + layout.reference_parameters.len();
        Self {
            next: vec![0; n],
            crc: vec![0; n],
        }
    }

    /// The parameter `index` of `layout` (a reference parameter when `reference`), the
    /// number of rows of its dimension, and its position in [`Unfilled::next`].
    fn find(layout: &Layout, reference: bool, index: usize) -> Option<(&Param, usize, usize)> {
        if reference {
            let p = layout.reference_parameters.get(index)?;
            Some((p, layout.n_references(), layout.parameters.len() + index))
        } else {
            Some((layout.parameters.get(index)?, layout.n_cases(), index))
        }
    }

    /// Writes `values` into the next rows of parameter `index` (see
    /// [`StudyWriter::write_parameter_rows`]).
    pub(super) fn write(
        &mut self,
        (file, path, layout): (&File, &Path, &Layout),
        reference: bool,
        index: usize,
        values: &ParamValues,
    ) -> Result<(), StudyFileError> {
        let refused = |variable: &str, reason: String| StudyFileError::Record {
            path: path.to_owned(),
            variable: variable.to_owned(),
            reason,
        };
        let what = if reference {
            "reference parameter"
        } else {
            "parameter"
        };
        let Some((param, rows, at)) = Self::find(layout, reference, index) else {
            return Err(refused(what, format!("the file has no {what} {index}")));
        };
        let name = param.spec.name.as_str();
        let start = self.next[at];
        let end = start + values.len();
        if end > rows {
            return Err(refused(
                name,
                format!("rows {start}..{end}, but the variable has {rows}"),
            ));
        }
        let ds = file.dataset(name).at(path, name)?;
        match (&param.values, values) {
            (ParamValues::F64(_), ParamValues::F64(v)) => {
                ds.write_slice(&v[..], start..end).at(path, name)?;
            }
            (ParamValues::Str(_), ParamValues::Str(v)) => {
                let strings = v
                    .iter()
                    .map(|s| attributes::vlen(s))
                    .collect::<hdf5::Result<Vec<_>>>()
                    .at(path, name)?;
                ds.write_slice(&strings[..], start..end).at(path, name)?;
                let crc = v
                    .iter()
                    .fold(self.crc[at], |crc, s| text::digest_continue(crc, s));
                text::write_digest_value(&ds, text::DIGEST_ATTR, crc).at(path, name)?;
                self.crc[at] = crc;
            }
            _ => {
                return Err(refused(
                    name,
                    "numbers for a text parameter, or text for a numeric one".to_owned(),
                ))
            }
        }
        self.next[at] = end;
        Ok(())
    }

    /// Refuses to finish while a parameter of `layout` has rows not written.
    pub(super) fn check_complete(
        &self,
        layout: &Layout,
        path: &Path,
    ) -> Result<(), StudyFileError> {
        let all = (layout.parameters.iter().map(|p| (p, layout.n_cases())))
            .chain((layout.reference_parameters.iter()).map(|p| (p, layout.n_references())));
        match all.zip(&self.next).find(|((_, rows), next)| *next != rows) {
            Some(((p, rows), next)) => Err(StudyFileError::Record {
                path: path.to_owned(),
                variable: p.spec.name.clone(),
                reason: format!("{next} of its {rows} rows written"),
            }),
            None => Ok(()),
        }
    }
}
