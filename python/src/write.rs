//! `tptd.write`: a mesh from Python written by the library's writers
//! ([`tptd::pipeline::write_mesh_file`]: the format by extension, under a temporary name
//! renamed when complete), with the options of `tptd-mesh`'s output checked as it checks
//! them.

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use tptd::io::msh::MshVersion;
use tptd::io::vtu::VtuEncoding;
use tptd::io::WriteOptions;
use tptd::pipeline::{check_applies, write_mesh_file, Given, Mode, Param};
use tptd::SurfaceOptions;

use crate::args::{invalid, PY_NAMES};
use crate::mesh_in::MeshArrays;
use crate::py_error;

/// The writers' options, as `tptd/__init__.py` passes them (`None`: not given).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct WriteArgs {
    msh_version: Option<String>,
    vtu_encoding: Option<String>,
    ascii: bool,
}

/// The `.msh` versions by name.
const MSH_VERSIONS: [(&str, MshVersion); 3] = [
    ("4.1", MshVersion::V41),
    ("2.2", MshVersion::V22),
    ("4.1-binary", MshVersion::V41Binary),
];

/// The `.vtu` encodings.
const VTU_ENCODINGS: [VtuEncoding; 3] = [VtuEncoding::Base64, VtuEncoding::Zlib, VtuEncoding::Raw];

/// The value named `name` among `values`, or the command line's message for `p`.
fn choice<T: Copy>(name: &str, p: Param, values: &[(&str, T)]) -> PyResult<T> {
    let found = values.iter().find(|(n, _)| *n == name).map(|&(_, v)| v);
    found.ok_or_else(|| {
        let names: Vec<&str> = values.iter().map(|&(n, _)| n).collect();
        invalid(name, p, format!("possible values: {}", names.join(", ")))
    })
}

impl WriteArgs {
    /// The writers' options for `path`, refused as the command line refuses them for its
    /// output (an unknown extension, an option of another format).
    fn options(&self, path: &std::path::Path) -> PyResult<WriteOptions> {
        let given: Vec<Param> = [
            (Param::MshVersion, self.msh_version.is_some()),
            (Param::VtuEncoding, self.vtu_encoding.is_some()),
            (Param::Ascii, self.ascii),
        ]
        .into_iter()
        .filter_map(|(p, set)| set.then_some(p))
        .collect();
        check_applies(&Given {
            mode: Mode::Mesh,
            params: &given,
            input: None,
            output: Some(path),
            transfer: None,
            threads: None,
        })
        .map_err(|e| PyValueError::new_err(e.render(PY_NAMES)))?;
        let mut opts = WriteOptions::default().with_ascii(self.ascii);
        if let Some(v) = &self.msh_version {
            opts = opts.with_msh_version(choice(v, Param::MshVersion, &MSH_VERSIONS)?);
        }
        if let Some(e) = &self.vtu_encoding {
            let named: Vec<(&str, VtuEncoding)> =
                VTU_ENCODINGS.iter().map(|&e| (e.name(), e)).collect();
            opts = opts.with_vtu_encoding(choice(e, Param::VtuEncoding, &named)?);
        }
        Ok(opts)
    }
}

/// Writes a mesh (its arrays, see [`MeshArrays`]) to `path` (see `tptd.write`).
#[pyfunction]
pub(crate) fn write_mesh(
    py: Python<'_>,
    path: PathBuf,
    mesh: MeshArrays<'_>,
    options: WriteArgs,
) -> PyResult<()> {
    let opts = options.options(&path)?;
    let mesh = mesh.into_mesh()?;
    let surface = SurfaceOptions::default();
    py.detach(|| write_mesh_file(&path, &mesh, &opts, &surface))
        .map_err(py_error)
}
