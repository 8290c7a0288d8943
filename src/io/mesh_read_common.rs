//! What every mesh reader shares: the [`MeshFile`] they return (the [`TetMesh`] plus the
//! named node groups and volume regions a solver needs for boundary conditions and
//! materials), the one-line [`MeshReadError`], reading a file with a parser
//! ([`parse_file`], [`parse_bytes`]), [`ParseError`] and the line-by-line text helpers.

use std::path::Path;

use super::read_common::ReadError;
use crate::mesh::{BoundaryLabel, TetMesh};

/// A mesh read from a file, with its named groups.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshFile {
    /// The tetrahedra and their nodes. `values` is the nodal field `f` when the file has one
    /// (`.msh` `$NodeData "f"`), zeros otherwise. `boundary` holds the triangles of the groups
    /// named `alpha`, `beta` and `box` (case-insensitive), labelled accordingly; the readers
    /// keep the file's orientation (`.msh`) or orient faces away from their tet (`.inp`).
    pub mesh: TetMesh,
    /// Named node groups (surface physical groups of a `.msh`, `*NSET`s of an `.inp`), names
    /// in lower case, nodes ascending and unique, in file order of the groups.
    pub node_groups: Vec<NodeGroup>,
    /// Names of the volume regions (physical volumes of a `.msh`, element sets of the
    /// `*ELEMENT` lines of an `.inp`), lower case.
    pub regions: Vec<String>,
    /// For every tet, its index in `regions` (empty when the file has no named volume).
    pub tet_region: Vec<u32>,
}

/// A named set of nodes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct NodeGroup {
    /// Lower-case name, e.g. `alpha`.
    pub name: String,
    /// 0-based node indices, ascending, unique.
    pub nodes: Vec<u32>,
}

impl MeshFile {
    /// The node group called `name` (case-insensitive), if any.
    pub fn group(&self, name: &str) -> Option<&NodeGroup> {
        let name = name.to_ascii_lowercase();
        self.node_groups.iter().find(|g| g.name == name)
    }
}

/// Why a mesh file could not be read. `Display` is one line starting with the path.
#[derive(Debug, thiserror::Error)]
pub enum MeshReadError {
    /// The file could not be opened or read.
    #[error("{file}: cannot read: {source}")]
    Io {
        /// The file.
        file: String,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The content is malformed, truncated, inconsistent or unsupported.
    #[error("{file}: {}{message}", at_line(*.line))]
    Invalid {
        /// The file.
        file: String,
        /// 1-based line number (0 when the problem is not tied to a line).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The extension is not one of [`MESH_EXTENSIONS`].
    #[error("{file}: unknown mesh format (expected {MESH_EXTENSIONS})")]
    UnknownFormat {
        /// The file.
        file: String,
    },
    /// A `.vtu` file the VTK XML reader refused (malformed, truncated or unsupported).
    #[error(transparent)]
    Vtk(#[from] ReadError),
}

/// The mesh file extensions [`super::read_mesh`] reads, for messages.
pub const MESH_EXTENSIONS: &str = ".msh, .inp, .vtu, .vtk, .mesh, .node or .ele";

/// Reads `path` as text and parses it with `parse`, the errors naming the file.
pub(crate) fn parse_file<T>(
    path: &Path,
    parse: impl FnOnce(&str) -> Result<T, ParseError>,
) -> Result<T, MeshReadError> {
    parse_bytes(path, |b| parse(&String::from_utf8_lossy(b)))
}

/// Reads `path` and parses its bytes with `parse`, the errors naming the file.
pub(crate) fn parse_bytes<T>(
    path: &Path,
    parse: impl FnOnce(&[u8]) -> Result<T, ParseError>,
) -> Result<T, MeshReadError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| MeshReadError::Io {
        file: file.clone(),
        source,
    })?;
    parse(&bytes).map_err(|e| MeshReadError::Invalid {
        file,
        line: e.line,
        message: e.message,
    })
}

/// `line N: ` for a line number, nothing for 0 (a problem not tied to a line).
fn at_line(line: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!("line {line}: ")
    }
}

/// A parse error without the file name (added by [`super::read_mesh`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    /// 1-based line number, 0 when not tied to a line.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for ParseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "line {}: {}", self.line, self.message)
    }
}

/// A [`ParseError`] at `line`.
pub(crate) fn perr(line: usize, message: impl Into<String>) -> ParseError {
    ParseError {
        line,
        message: message.into(),
    }
}

/// Non-empty lines with their 1-based numbers, and typed field parsing.
pub(crate) struct Lines<'a> {
    inner: std::iter::Enumerate<std::str::Lines<'a>>,
    /// Number of the line returned last.
    pub(crate) line: usize,
}

impl<'a> Lines<'a> {
    pub(crate) fn new(text: &'a str) -> Self {
        Lines {
            inner: text.lines().enumerate(),
            line: 0,
        }
    }

    /// The next line that is not blank, trimmed, or `None` at the end.
    pub(crate) fn next_line(&mut self) -> Option<&'a str> {
        for (i, l) in self.inner.by_ref() {
            let t = l.trim();
            if !t.is_empty() {
                self.line = i + 1;
                return Some(t);
            }
        }
        None
    }

    /// The next non-blank line, or an error naming `what` was expected.
    pub(crate) fn expect(&mut self, what: &str) -> Result<&'a str, ParseError> {
        let line = self.line;
        self.next_line()
            .ok_or_else(|| perr(line, format!("unexpected end of file, expected {what}")))
    }

    /// An error at the current line.
    pub(crate) fn err(&self, message: impl Into<String>) -> ParseError {
        perr(self.line, message)
    }
}

/// Parses `s` as a `T`, or an error at `line` naming `what`.
pub(crate) fn field<T: std::str::FromStr>(
    s: &str,
    line: usize,
    what: &str,
) -> Result<T, ParseError> {
    s.trim()
        .parse()
        .map_err(|_| perr(line, format!("invalid {what} {s:?}")))
}

/// The boundary label of a group name (`alpha`, `beta`, `box`, any case).
pub(crate) fn label_of(name: &str) -> Option<BoundaryLabel> {
    BoundaryLabel::ALL
        .into_iter()
        .find(|l| l.name().eq_ignore_ascii_case(name))
}

/// Checks the assembled mesh: at least one tet, every tet's nodes distinct.
pub(crate) fn check_mesh(mesh: &TetMesh) -> Result<(), ParseError> {
    if mesh.tets.is_empty() {
        return Err(perr(0, "no tetrahedra in the file"));
    }
    for (t, tet) in mesh.tets.iter().enumerate() {
        if (0..4).any(|a| (a + 1..4).any(|b| tet[a] == tet[b])) {
            return Err(perr(0, format!("tetrahedron {} repeats a node", t + 1)));
        }
    }
    Ok(())
}

/// Sorts and deduplicates the nodes of every group.
pub(crate) fn normalize_groups(groups: &mut [NodeGroup]) {
    for g in groups {
        g.nodes.sort_unstable();
        g.nodes.dedup();
    }
}
