//! Creating a study file: its access properties, the dimensions and coordinate
//! variables, and every variable of the layout with its storage, checksums and
//! attributes.

use super::*;

/// How the writer opens files: HDF5's metadata cache bounded
/// ([`bounded_metadata_cache`]), and no small-data aggregation, so that every chunk,
/// however small, is given new space at the end of the file: where
/// [`StudyWriter::file_len`] says a crash journal finds it.
pub(super) fn file_access(p: &mut FileAccessBuilder) -> &mut FileAccessBuilder {
    p.mdc_config(&bounded_metadata_cache())
        .small_data_block_size(0)
}

/// HDF5's metadata cache configuration bounded to [`METADATA_CACHE_BYTES`] (its
/// adaptive resizing stays between half and all of it).
pub(in crate::output) fn bounded_metadata_cache() -> MetadataCacheConfig {
    MetadataCacheConfig {
        set_initial_size: true,
        initial_size: METADATA_CACHE_BYTES / 2,
        min_size: METADATA_CACHE_BYTES / 2,
        max_size: METADATA_CACHE_BYTES,
        ..MetadataCacheConfig::default()
    }
}

/// Lays out a new file.
pub(super) struct Creator<'a> {
    pub(super) path: &'a Path,
    pub(super) file: &'a File,
    pub(super) layout: &'a Layout,
    /// Whether the parameters are left unwritten ([`StudyWriter::create_unfilled`]).
    pub(super) unfilled: bool,
}

/// The coordinate variables: name, units, long name. Their order is their netCDF
/// dimension id.
pub(super) const COORDINATES: [(&str, &str, &str); 4] = [
    (CASE, "1", "case id"),
    (TIME, TIME_UNITS, "time from the start of the simulation"),
    (FREQUENCY, "Hz", "frequency"),
    (REFERENCE, "1", "reference run id"),
];

/// The further attributes of `time`, which make it a CF time coordinate whose
/// reference date ([`TIME_UNITS`]) is nominal.
pub(super) const TIME_ATTRIBUTES: [(&str, &str); 4] = [
    ("standard_name", "time"),
    ("axis", "T"),
    ("calendar", "standard"),
    (
        "comment",
        "seconds from the start of the simulation; the reference date is nominal (a CF \
         time coordinate needs one): open with decode_times=False in xarray to read seconds",
    ),
];

impl Creator<'_> {
    /// The `[case]` variables every file has: each case's reference row (in a file
    /// with references), its status (a CF flag variable) and its error message.
    fn case_variables(&self, case: &Dataset) -> Result<(), StudyFileError> {
        let l = self.layout;
        if !l.reference_ids.is_empty() {
            let spec = VarSpec::new(
                REFERENCE_INDEX,
                "1",
                "row of the reference run this case is compared with",
            );
            let ds = self.with_data(&spec.name, &ids32(&l.reference_index))?;
            self.finish_var(&ds, &spec, None, &[case])?;
        }

        let spec = VarSpec::new(STATUS, "1", "case status");
        let ds = self.empty::<i8>(STATUS, &[l.n_cases()], Status::Pending.code())?;
        self.finish_var(&ds, &spec, None, &[case])?;
        status_flags(&ds).at(self.path, STATUS)?;

        let spec = VarSpec::new(
            ERROR_MESSAGE,
            "1",
            "why the case failed (empty if it did not)",
        );
        // Empty strings rather than HDF5's null fill, which netCDF-C shows as NIL.
        let empty = vec![VarLenUnicode::new(); l.n_cases()];
        let ds = self.with_data(ERROR_MESSAGE, &empty)?;
        text::write_digest(&ds, text::DIGEST_ATTR, &vec![""; l.n_cases()])
            .at(self.path, ERROR_MESSAGE)?;
        self.finish_var(&ds, &spec, None, &[case])?;

        Ok(())
    }

    /// The `[case, replicate]` variables of a file with replicates: each replicate's
    /// status (a CF flag variable) and error message, written whole like the
    /// replicate metrics.
    fn replicate_variables(
        &self,
        case: &Dataset,
        replicate: &Dataset,
    ) -> Result<(), StudyFileError> {
        let shape = [self.layout.n_cases(), self.layout.replicates.len()];
        let spec = VarSpec::new(REPLICATE_STATUS, "1", "replicate status");
        let ds = self
            .file
            .new_dataset::<i8>()
            .fill_value(Status::Pending.code())
            .chunk(whole_chunks(&shape))
            .fletcher32()
            .shape(shape)
            .create(REPLICATE_STATUS)
            .at(self.path, REPLICATE_STATUS)?;
        self.finish_var(&ds, &spec, None, &[case, replicate])?;
        status_flags(&ds).at(self.path, REPLICATE_STATUS)?;

        let name = REPLICATE_ERROR_MESSAGE;
        let spec = VarSpec::new(name, "1", "why the replicate failed (empty if it did not)");
        let empty = vec![String::new(); shape[0] * shape[1]];
        let ds = self
            .file
            .new_dataset::<VarLenUnicode>()
            .shape(shape)
            .create(name)
            .and_then(|ds| super::write_strings(&ds, &empty).map(|()| ds))
            .at(self.path, name)?;
        self.finish_var(&ds, &spec, None, &[case, replicate])
    }

    /// Creates every dimension and variable of the layout, with the root attributes.
    pub(super) fn build(&self) -> Result<(), StudyFileError> {
        let l = self.layout;
        self.root_attributes()?;
        let (case, time, frequency, reference) = self.coordinates()?;

        for p in &l.parameters {
            self.parameter(p, Role::Parameter, &case)?;
        }
        self.case_variables(&case)?;
        for spec in &l.metrics {
            let ds = self.empty::<f64>(&spec.name, &[l.n_cases()], f64::NAN)?;
            self.finish_var(&ds, spec, Some(Role::Metric), &[&case])?;
            fill_attr(&ds, false).at(self.path, &spec.name)?;
        }
        let mut dimid = COORDINATES.len() - usize::from(time.is_none());
        for (name, ids, meta, specs, role) in [
            (
                REPLICATE,
                &l.replicates,
                ("1", "replicate id (0: the case unperturbed)"),
                &l.replicate_metrics,
                Role::ReplicateMetric,
            ),
            (
                REVOLUTION,
                &l.revolutions,
                ("1", "whole crank revolution after the transient"),
                &l.revolution_metrics,
                Role::RevolutionMetric,
            ),
        ] {
            if !ids.is_empty() {
                let dim = self.coordinate(name, &ids32(ids), meta, dimid)?;
                dimid += 1;
                if name == REPLICATE {
                    self.replicate_variables(&case, &dim)?;
                }
                self.whole_rows(&dim, ids.len(), specs, role, &case)?;
            }
        }
        if !l.orders.is_empty() {
            let meta = ("1", "order: cycles per crank revolution");
            let dim = self.coordinate(ORDER, &l.orders, meta, dimid)?;
            dimid += 1;
            self.whole_rows(
                &dim,
                l.orders.len(),
                &l.order_spectra,
                Role::OrderSpectrum,
                &case,
            )?;
        }
        // The layout was validated: a file with series has times.
        for spec in &l.series {
            self.array(spec, Role::Series, &case, time.as_ref().expect("times"))?;
        }
        for spec in &l.spectra {
            self.array(spec, Role::Spectrum, &case, &frequency)?;
        }
        if !l.sk_frequencies.is_empty() {
            let meta = ("Hz", "frequency of the spectral kurtosis (STFT bin)");
            let dim = self.coordinate(SK_FREQUENCY, &l.sk_frequencies, meta, dimid)?;
            for spec in &l.kurtosis {
                self.array(spec, Role::SpectralKurtosis, &case, &dim)?;
            }
        }
        for p in &l.reference_parameters {
            self.parameter(p, Role::ReferenceParameter, &reference)?;
        }
        for spec in &l.reference_series {
            let time = time.as_ref().expect("times");
            self.array(spec, Role::ReferenceSeries, &reference, time)?;
        }
        Ok(())
    }

    /// The format version, the layout's root attributes and the digest of its
    /// variables' names and roles.
    fn root_attributes(&self) -> Result<(), StudyFileError> {
        attributes::write(self.file, FORMAT_ATTR, &FORMAT_VERSION.into())
            .at(self.path, FORMAT_ATTR)?;
        for (name, value) in &self.layout.attributes {
            attributes::write(self.file, name, value).at(self.path, name)?;
        }
        let digest = text::variables_digest(self.layout);
        attributes::write(self.file, VARIABLES_DIGEST_ATTR, &digest.into())
            .at(self.path, VARIABLES_DIGEST_ATTR)
    }

    /// The `[case, dim]` variables `specs` (`len` columns), float64, checksummed in
    /// [`whole_chunks`]: written whole, like the `[case]` metrics.
    pub(super) fn whole_rows(
        &self,
        dim: &Dataset,
        len: usize,
        specs: &[VarSpec],
        role: Role,
        case: &Dataset,
    ) -> Result<(), StudyFileError> {
        for spec in specs {
            let shape = [self.layout.n_cases(), len];
            let ds = self
                .file
                .new_dataset::<f64>()
                .fill_value(f64::NAN)
                .chunk(whole_chunks(&shape))
                .fletcher32()
                .shape(shape)
                .create(spec.name.as_str())
                .at(self.path, &spec.name)?;
            self.finish_var(&ds, spec, Some(role), &[case, dim])?;
            fill_attr(&ds, false).at(self.path, &spec.name)?;
        }
        Ok(())
    }

    /// Writes the coordinate variables and makes them dimension scales: `case`,
    /// `time` (left out when the layout has no times: then no variable uses it),
    /// `frequency` and `reference`, with consecutive netCDF dimension ids.
    pub(super) fn coordinates(
        &self,
    ) -> Result<(Dataset, Option<Dataset>, Dataset, Dataset), StudyFileError> {
        let l = self.layout;
        let [case, time, frequency, reference] = COORDINATES;
        let meta =
            |(_, units, long_name): (&'static str, &'static str, &'static str)| (units, long_name);
        let case = self.coordinate(CASE, &ids32(&l.case_ids), meta(case), 0)?;
        let time = (!l.times.is_empty())
            .then(|| {
                let ds = self.coordinate(TIME, &l.times, meta(time), 1)?;
                for (name, value) in TIME_ATTRIBUTES {
                    attributes::write_str(&ds, name, value).at(self.path, TIME)?;
                }
                Ok(ds)
            })
            .transpose()?;
        let next = 1 + usize::from(time.is_some());
        Ok((
            case,
            time,
            self.coordinate(FREQUENCY, &l.frequencies, meta(frequency), next)?,
            self.coordinate(
                REFERENCE,
                &ids32(&l.reference_ids),
                meta(reference),
                next + 1,
            )?,
        ))
    }

    /// A coordinate variable `name` holding `values`, with `(units, long_name)`,
    /// made a dimension scale with netCDF-C's dimension id `dimid`.
    pub(super) fn coordinate<T: H5Type>(
        &self,
        name: &str,
        values: &[T],
        (units, long_name): (&str, &str),
        dimid: usize,
    ) -> Result<Dataset, StudyFileError> {
        let ds = self.with_data(name, values)?;
        set_scale(&ds, name).map_err(|source| StudyFileError::Scale {
            path: self.path.to_owned(),
            variable: name.to_owned(),
            source,
        })?;
        attributes::write_str(&ds, "units", units).at(self.path, name)?;
        attributes::write_str(&ds, "long_name", long_name).at(self.path, name)?;
        text::write_digest(&ds, text::ATTRIBUTES_DIGEST_ATTR, &[units, long_name, ""])
            .at(self.path, name)?;
        // netCDF-C's dimension id, kept in file order like netCDF-C writes it.
        ds.new_attr::<i32>()
            .create("_Netcdf4Dimid")
            .and_then(|a| a.write_scalar(&(dimid as i32)))
            .at(self.path, name)?;
        Ok(ds)
    }

    /// A `[dim]` parameter with its values (unwritten, one row per `dim` value, when
    /// the file is made unfilled).
    pub(super) fn parameter(
        &self,
        p: &Param,
        role: Role,
        dim: &Dataset,
    ) -> Result<(), StudyFileError> {
        let name = p.spec.name.as_str();
        let rows = [dim.size()];
        let ds = match &p.values {
            ParamValues::F64(_) if self.unfilled => {
                let builder = self.file.new_dataset::<f64>().chunk(whole_chunks(&rows));
                builder
                    .fletcher32()
                    .shape(rows)
                    .create(name)
                    .at(self.path, name)?
            }
            ParamValues::Str(_) if self.unfilled => {
                let builder = self.file.new_dataset::<VarLenUnicode>().shape(rows);
                let ds = builder.create(name).at(self.path, name)?;
                // Continued as the blocks are written (`writer::parameters`).
                text::write_digest::<&str>(&ds, text::DIGEST_ATTR, &[]).at(self.path, name)?;
                ds
            }
            ParamValues::F64(v) => self.with_data(&p.spec.name, v)?,
            ParamValues::Str(v) => {
                let strings = v
                    .iter()
                    .map(|s| attributes::vlen(s))
                    .collect::<hdf5::Result<Vec<_>>>()
                    .at(self.path, &p.spec.name)?;
                let ds = self.with_data(&p.spec.name, &strings)?;
                text::write_digest(&ds, text::DIGEST_ATTR, v).at(self.path, &p.spec.name)?;
                ds
            }
        };
        self.finish_var(&ds, &p.spec, Some(role), &[dim])
    }

    /// A `[rows, len]` series or spectrum variable: chunked by row, NaN-filled,
    /// compressed as the storage options say.
    pub(super) fn array(
        &self,
        spec: &VarSpec,
        role: Role,
        rows: &Dataset,
        cols: &Dataset,
    ) -> Result<(), StudyFileError> {
        let shape = [rows.size(), cols.size()];
        let ds = if self.layout.storage.float32 {
            self.empty::<f32>(&spec.name, &shape, f32::NAN)?
        } else {
            self.empty::<f64>(&spec.name, &shape, f64::NAN)?
        };
        self.finish_var(&ds, spec, Some(role), &[rows, cols])?;
        fill_attr(&ds, self.layout.storage.float32).at(self.path, &spec.name)
    }

    /// A 1-D variable holding `data`: numbers checksummed (Fletcher-32, in
    /// [`whole_chunks`]); variable-length strings contiguous, as HDF5 applies no
    /// filter to them (their digest attribute checks them, see `text`).
    pub(super) fn with_data<T: H5Type>(
        &self,
        name: &str,
        data: &[T],
    ) -> Result<Dataset, StudyFileError> {
        let builder = self.file.new_dataset_builder().with_data(data);
        let builder = if is_string::<T>() {
            builder
        } else {
            builder.chunk(whole_chunks(&[data.len()])).fletcher32()
        };
        builder.create(name).at(self.path, name)
    }

    /// An unwritten variable of `shape` with `fill`, checksummed (Fletcher-32); 2-D
    /// variables are chunked one row per chunk and filtered per the storage options
    /// (shuffle and deflate before the checksum), 1-D ones as [`whole_chunks`] says.
    pub(super) fn empty<T: H5Type>(
        &self,
        name: &str,
        shape: &[usize],
        fill: T,
    ) -> Result<Dataset, StudyFileError> {
        let mut builder = self.file.new_dataset::<T>().fill_value(fill);
        if let [_, cols] = *shape {
            builder = builder
                .chunk((1, cols.max(1)))
                .set_filters(&encode::filters(self.layout.storage));
        } else {
            builder = builder.chunk(whole_chunks(shape)).fletcher32();
        }
        builder.shape(shape).create(name).at(self.path, name)
    }

    /// Attaches the dimension scales and writes `units`, `long_name`, the attributes
    /// saying how the variable was made, and the role.
    pub(super) fn finish_var(
        &self,
        ds: &Dataset,
        spec: &VarSpec,
        role: Option<Role>,
        dims: &[&Dataset],
    ) -> Result<(), StudyFileError> {
        let name = spec.name.as_str();
        for (idx, dim) in dims.iter().enumerate() {
            attach_scale(ds, dim, idx).map_err(|source| StudyFileError::Scale {
                path: self.path.to_owned(),
                variable: name.to_owned(),
                source,
            })?;
        }
        attributes::write_str(ds, "units", &spec.units).at(self.path, name)?;
        attributes::write_str(ds, "long_name", &spec.long_name).at(self.path, name)?;
        for (attribute, value) in &spec.attributes {
            attributes::write(ds, attribute, value).at(self.path, name)?;
        }
        if let Some(role) = role {
            attributes::write_str(ds, ROLE_ATTR, role.as_str()).at(self.path, name)?;
        }
        let described = text::digested(
            &[
                spec.units.as_str(),
                &spec.long_name,
                role.map_or("", Role::as_str),
            ],
            &spec.attributes,
        );
        text::write_digest(ds, text::ATTRIBUTES_DIGEST_ATTR, &described).at(self.path, name)
    }
}

/// The CF flag attributes of a [`Status`] variable.
fn status_flags(ds: &Dataset) -> hdf5::Result<()> {
    let flags: Vec<i8> = Status::ALL.iter().map(|s| s.code()).collect();
    ds.new_attr_builder()
        .with_data(&flags[..])
        .create("flag_values")?;
    attributes::write_str(ds, "flag_meanings", Status::FLAG_MEANINGS)
}

/// Elements in a chunk of a variable written whole (1-D variables, `[case, dim]`
/// metrics): 512 KiB of float64, so a chunk fits HDF5's 1 MiB chunk cache and reading
/// the cases one by one reads each chunk (and checks its checksum) once.
pub(super) const WHOLE_CHUNK_ELEMENTS: usize = 1 << 16;

/// The chunk shape of a variable of `shape` written whole: whole rows, as many as
/// [`WHOLE_CHUNK_ELEMENTS`] allows (at least one); every extent at least 1, as HDF5
/// needs, also for an empty variable.
pub(super) fn whole_chunks(shape: &[usize]) -> Vec<usize> {
    let cols: usize = shape.iter().skip(1).product::<usize>().max(1);
    let rows = (WHOLE_CHUNK_ELEMENTS / cols).clamp(1, shape.first().copied().unwrap_or(1).max(1));
    std::iter::once(rows)
        .chain(shape.iter().skip(1).map(|&d| d.max(1)))
        .collect()
}

/// Whether `T` is a variable-length string type.
pub(super) fn is_string<T: H5Type>() -> bool {
    matches!(
        T::type_descriptor(),
        TypeDescriptor::VarLenUnicode | TypeDescriptor::VarLenAscii
    )
}

/// Ids as stored: int32, CF-1.8's widest integer (the layout checked that they fit).
pub(super) fn ids32(ids: &[u64]) -> Vec<i32> {
    ids.iter()
        .map(|&id| i32::try_from(id).unwrap_or(i32::MAX))
        .collect()
}

/// Writes the CF `_FillValue` attribute (NaN, of the variable's type).
pub(super) fn fill_attr(ds: &Dataset, float32: bool) -> hdf5::Result<()> {
    if float32 {
        ds.new_attr::<f32>()
            .create("_FillValue")?
            .write_scalar(&f32::NAN)
    } else {
        ds.new_attr::<f64>()
            .create("_FillValue")?
            .write_scalar(&f64::NAN)
    }
}
