//! The keyword arguments of `tptd.mesh` and `tptd.mesh_file` as the library's request: each
//! value checked by the library's parser for it ([`tptd::pipeline::values`]), then the
//! library's check that every argument given applies ([`check_applies`]), every message
//! naming the parameters the Python way ([`PY_NAMES`]).

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tptd::grade::{GradeOptions, DEFAULT_GRADING};
use tptd::improve::QualityOptions;
use tptd::pipeline::values;
use tptd::pipeline::{check_applies, Given, MeshRequest, Mode, Param, ParamNames, QualityRequest};
use tptd::sdf::SurfaceGridOptions;
use tptd::Method;

/// Python spells every parameter by its neutral name, except the input file (`path`) and the
/// analysis switched off (`analysis=False`).
fn py_name(p: Param) -> &'static str {
    match p {
        Param::Input => "path",
        Param::NoAnalysis => "analysis=False",
        p => p.name(),
    }
}

/// The library's messages name the parameters as the Python functions do.
pub(crate) const PY_NAMES: ParamNames = ParamNames(py_name);

/// The bound `v` (if given) through the library's parser, named by `names` in messages.
pub(crate) fn bound(v: Option<f64>, p: Param, names: ParamNames) -> PyResult<Option<f64>> {
    let parse = |v: f64| {
        let text = v.to_string();
        values::bound(&text).map_err(|e| invalid_named(names, &text, p, e))
    };
    v.map(parse).transpose()
}

/// The spacing (if given) through the library's parser.
pub(crate) fn spacing(s: Option<[f64; 3]>) -> PyResult<Option<[f64; 3]>> {
    let Some([x, y, z]) = s else {
        return Ok(None);
    };
    let text = format!("{x},{y},{z}");
    values::spacing(&text)
        .map(Some)
        .map_err(|e| invalid(&text, Param::Spacing, e))
}

/// The thread count (if given): 1 or more.
pub(crate) fn threads(n: Option<i64>) -> PyResult<Option<usize>> {
    match n {
        None => Ok(None),
        Some(n) if n >= 1 => Ok(Some(n as usize)),
        Some(n) => Err(invalid(
            n,
            Param::Threads,
            "expected 1 or more worker threads",
        )),
    }
}

/// The methods, by name.
const METHODS: [Method; 5] = [
    Method::Ctd,
    Method::Tptd,
    Method::Std,
    Method::Six,
    Method::Five,
];

/// The keyword arguments, as `tptd/__init__.py` passes them (every key present; `None` for
/// one not given).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct Options {
    pub(crate) alpha: Option<f64>,
    pub(crate) beta: Option<f64>,
    pub(crate) levels: Option<Vec<f64>>,
    pub(crate) region_names: Option<Vec<String>>,
    pub(crate) spacing: Option<[f64; 3]>,
    pub(crate) origin: [f64; 3],
    pub(crate) affine: Option<[[f64; 4]; 4]>,
    pub(crate) method: String,
    pub(crate) quality: bool,
    pub(crate) min_angle: f64,
    pub(crate) max_angle: f64,
    pub(crate) quality_time: Option<f64>,
    pub(crate) check: bool,
    pub(crate) analysis: bool,
    pub(crate) threads: Option<i64>,
    pub(crate) field: Option<String>,
    pub(crate) function: Option<PathBuf>,
    pub(crate) resolution: Option<i64>,
    pub(crate) voxel_size: Option<f64>,
    pub(crate) memory_limit: Option<i64>,
    pub(crate) max_edge: Option<f64>,
    pub(crate) grading: f64,
}

/// The names of `tptd.isosurface`: its level is the lower bound of the interval meshed.
fn iso_name(p: Param) -> &'static str {
    match p {
        Param::Alpha => "level",
        p => py_name(p),
    }
}

/// The library's messages name the parameters as `tptd.isosurface` does.
pub(crate) const ISO_NAMES: ParamNames = ParamNames(iso_name);

/// `invalid value '{value}' for {param}: {problem}`, as the command line says it.
pub(crate) fn invalid(
    value: impl std::fmt::Display,
    p: Param,
    problem: impl std::fmt::Display,
) -> PyErr {
    invalid_named(PY_NAMES, value, p, problem)
}

/// [`invalid`] with the parameter named by `names`.
fn invalid_named(
    names: ParamNames,
    value: impl std::fmt::Display,
    p: Param,
    problem: impl std::fmt::Display,
) -> PyErr {
    PyValueError::new_err(format!(
        "invalid value '{value}' for {}: {problem}",
        names.of(p)
    ))
}

/// `v` through the library's parser of the parameter `p` (given its text).
pub(crate) fn parsed<T>(v: f64, p: Param, parse: fn(&str) -> Result<T, String>) -> PyResult<T> {
    let text = v.to_string();
    parse(&text).map_err(|e| invalid(&text, p, e))
}

impl Options {
    /// The parameters given (not left at their defaults).
    fn given(&self) -> Vec<Param> {
        let q = QualityOptions::default();
        let set = [
            (Param::Alpha, self.alpha.is_some()),
            (Param::Beta, self.beta.is_some()),
            (Param::Levels, self.levels.is_some()),
            (Param::RegionNames, self.region_names.is_some()),
            (Param::Spacing, self.spacing.is_some()),
            (Param::Method, self.method != "ctd"),
            (Param::Quality, self.quality),
            (Param::MinAngle, self.min_angle != q.min_angle),
            (Param::MaxAngle, self.max_angle != q.max_angle),
            (Param::QualityTime, self.quality_time.is_some()),
            (Param::Check, self.check),
            (Param::NoAnalysis, !self.analysis),
            (Param::Threads, self.threads.is_some()),
            (Param::Field, self.field.is_some()),
            (Param::Function, self.function.is_some()),
            (Param::Resolution, self.resolution.is_some()),
            (Param::VoxelSize, self.voxel_size.is_some()),
            (Param::MemoryLimit, self.memory_limit.is_some()),
            (Param::MaxEdge, self.max_edge.is_some()),
            (Param::Grading, self.grading != DEFAULT_GRADING),
        ];
        set.into_iter()
            .filter(|&(_, s)| s)
            .map(|(p, _)| p)
            .collect()
    }

    /// The request of the arguments (`input`: the file of `mesh_file`, `None` for an array),
    /// each value and then the whole checked as the command line checks them.
    ///
    /// # Errors
    /// `ValueError` with the library's message.
    pub(crate) fn request(&self, input: Option<PathBuf>) -> PyResult<MeshRequest> {
        self.request_named(input, PY_NAMES)
    }

    /// [`Options::request`] with the parameters named by `names` in messages.
    pub(crate) fn request_named(
        &self,
        input: Option<PathBuf>,
        names: ParamNames,
    ) -> PyResult<MeshRequest> {
        let threads = self.threads()?;
        let method = self.method()?;
        if self.affine.is_some() && self.spacing.is_some() {
            return Err(PyValueError::new_err(
                "affine and spacing exclude each other: give one",
            ));
        }
        let given = self.given();
        check_applies(&Given {
            mode: Mode::Mesh,
            params: &given,
            input: input.as_deref(),
            output: None,
            transfer: None,
            threads,
        })
        .map_err(|e| PyValueError::new_err(e.render(names)))?;
        Ok(MeshRequest {
            input,
            function: self.function.clone(),
            field: self.field.clone(),
            spacing: self.spacing()?,
            surface_grid: self.surface_grid()?,
            alpha: bound(self.alpha, Param::Alpha, names)?,
            beta: bound(self.beta, Param::Beta, names)?,
            levels: self.levels()?,
            region_names: self.region_names.clone().unwrap_or_default(),
            method,
            threads,
            quality: self.quality()?,
            grade: self.grade()?,
            check: self.check,
            analysis: self.analysis,
            memory_limit: self.memory_limit()?,
            names,
            ..MeshRequest::default()
        })
    }

    fn levels(&self) -> PyResult<Option<Vec<f64>>> {
        let Some(levels) = &self.levels else {
            return Ok(None);
        };
        let checked: PyResult<Vec<f64>> = levels
            .iter()
            .map(|&l| parsed(l, Param::Levels, values::bound))
            .collect();
        checked.map(Some)
    }

    fn spacing(&self) -> PyResult<Option<[f64; 3]>> {
        spacing(self.spacing)
    }

    fn method(&self) -> PyResult<Method> {
        METHODS
            .into_iter()
            .find(|m| m.name() == self.method)
            .ok_or_else(|| {
                let names: Vec<&str> = METHODS.iter().map(|m| m.name()).collect();
                invalid(
                    &self.method,
                    Param::Method,
                    format!("possible values: {}", names.join(", ")),
                )
            })
    }

    fn threads(&self) -> PyResult<Option<usize>> {
        threads(self.threads)
    }

    fn memory_limit(&self) -> PyResult<Option<u64>> {
        match self.memory_limit {
            None => Ok(None),
            Some(n) if n >= 1 => Ok(Some(n as u64)),
            Some(n) => Err(invalid(
                n,
                Param::MemoryLimit,
                "expected a positive number of bytes",
            )),
        }
    }

    fn grade(&self) -> PyResult<Option<GradeOptions>> {
        let Some(max_edge) = self.max_edge else {
            return Ok(None);
        };
        Ok(Some(GradeOptions {
            max_edge: parsed(max_edge, Param::MaxEdge, values::positive)?,
            grading: parsed(self.grading, Param::Grading, values::positive)?,
        }))
    }

    fn quality(&self) -> PyResult<Option<QualityRequest>> {
        if !self.quality {
            return Ok(None);
        }
        let seconds = self
            .quality_time
            .map(|t| parsed(t, Param::QualityTime, values::seconds))
            .transpose()?;
        Ok(Some(QualityRequest {
            options: QualityOptions {
                min_angle: parsed(self.min_angle, Param::MinAngle, values::min_angle)?,
                max_angle: parsed(self.max_angle, Param::MaxAngle, values::max_angle)?,
                time_budget: None,
                ..QualityOptions::default()
            },
            seconds,
        }))
    }

    fn surface_grid(&self) -> PyResult<SurfaceGridOptions> {
        let resolution = match self.resolution {
            Some(n) if n < 1 => {
                return Err(invalid(n, Param::Resolution, "expected 1 or more voxels"))
            }
            n => n.map(|n| n as usize),
        };
        let voxel_size = self
            .voxel_size
            .map(|h| parsed(h, Param::VoxelSize, values::positive))
            .transpose()?;
        Ok(SurfaceGridOptions {
            resolution,
            voxel_size,
            ..SurfaceGridOptions::default()
        })
    }
}
