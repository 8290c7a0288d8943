//! Command-line arguments: the clap definition and the value parsers.

use std::path::PathBuf;

use clap::{Parser, ValueEnum};
use tptd::critical::{CriticalKind, TransferDesign};
use tptd::io::msh::MshVersion;
use tptd::io::vtu::VtuEncoding;
use tptd::Method;

/// Mesh the interval volume {alpha <= f <= beta} of a 3-D scalar grid into tetrahedra, with
/// the topology of the trilinear interpolant.
///
/// Grid values equal to a bound count as outside the interval. Lengths and volumes are in the
/// units of the file's coordinates (millimetres for NIfTI and most NRRD and MetaImage
/// images; voxels for .npy, whose spacing is 1 unless --spacing says otherwise).
#[derive(Parser, Debug)]
#[command(name = "tptd-mesh", version)]
pub(crate) struct Cli {
    /// Input volume (.npy, .nrrd, .nhdr, .nii, .nii.gz, .mhd, .mha), or a curvilinear grid
    /// (.vts, or a Plot3D .xyz with its .q or .f file)
    #[arg(value_name = "INPUT", required_unless_present_any = ["demo", "inspect"])]
    pub(crate) input: Option<PathBuf>,

    /// Output mesh; the format follows the extension: .msh (Gmsh), .inp (Abaqus/CalculiX),
    /// .vtu (VTK) for tetrahedra; .obj, .ply, .stl for the isosurface (the level sets
    /// f = alpha and f = beta, normals towards increasing f) [default with --demo:
    /// tptd-demo.vtu]
    #[arg(short, long, value_name = "OUT", required_unless_present_any = ["demo", "critical", "inspect"])]
    pub(crate) output: Option<PathBuf>,

    /// Lower bound of the interval [default: -inf; at least one of --alpha/--beta is required]
    #[arg(long, value_name = "A", allow_hyphen_values = true, value_parser = parse_bound)]
    pub(crate) alpha: Option<f64>,

    /// Upper bound of the interval [default: inf]
    #[arg(long, value_name = "B", allow_hyphen_values = true, value_parser = parse_bound)]
    pub(crate) beta: Option<f64>,

    /// Cell decomposition: ctd and tptd keep the topology of the trilinear interpolant (ctd with
    /// fewer tets); std keeps it except in cells both bounds cross; six and five do not
    #[arg(long, value_enum, default_value_t = MethodArg::Ctd)]
    pub(crate) method: MethodArg,

    /// Also write a JSON report of the run to this file
    #[arg(long, value_name = "FILE.json")]
    pub(crate) report: Option<PathBuf>,

    /// Worker threads [default: all cores]
    #[arg(short = 'j', long, value_name = "N", allow_hyphen_values = true, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub(crate) threads: Option<u32>,

    /// Gmsh file format version for .msh output: 4.1 (ASCII), 2.2 (ASCII) or 4.1-binary (the
    /// content of 4.1 in Gmsh's binary encoding: faster to write and for Gmsh to read)
    #[arg(long, value_enum, value_name = "VERSION", default_value_t = MshVersionArg::V41)]
    pub(crate) msh_version: MshVersionArg,

    /// Data encoding of .vtu output: base64 (read by meshio, VTK and ParaView), zlib
    /// (compressed, as VTK writes; smallest, slowest) or raw (fastest; meshio cannot read it)
    #[arg(long, value_enum, value_name = "ENCODING", default_value_t = VtuEncodingArg::Base64)]
    pub(crate) vtu_encoding: VtuEncodingArg,

    /// Override the grid spacing (physical size of a voxel, in the file's units, e.g. mm),
    /// e.g. 0.5,0.5,1.2
    #[arg(long, value_name = "SX,SY,SZ", allow_hyphen_values = true, value_parser = parse_spacing)]
    pub(crate) spacing: Option<Spacing>,

    /// Curvilinear input: the point-data scalar (.vts) or variable (Plot3D: a name such as
    /// density, or a 1-based number) to mesh [default: the first]
    #[arg(long, value_name = "NAME")]
    pub(crate) field: Option<String>,

    /// Plot3D input: the function file (.q or .f) [default: the grid's name with .q, else .f]
    #[arg(long, value_name = "FILE")]
    pub(crate) function: Option<PathBuf>,

    /// Surface output: also write the triangles on the grid box that close the surface
    #[arg(long)]
    pub(crate) caps: bool,

    /// Surface output: ASCII instead of binary .ply / .stl
    #[arg(long)]
    pub(crate) ascii: bool,

    /// Skip the Betti numbers and dihedral angles
    #[arg(long)]
    pub(crate) no_analysis: bool,

    /// Check the mesh before writing it: conforming, every tet positive, a closed manifold
    /// boundary that does not meet itself, the tets covering the domain once (winding number
    /// 1 at sampled tets), alpha and beta triangles near their trilinear level sets: within
    /// half a voxel with ctd and tptd, within a cell's diagonal with std, six and five, which
    /// interpolate linearly across cells and change the topology at saddles (in parameter
    /// space on curvilinear grids). A failed check is an error and writes nothing. The mesh
    /// is then held in memory, also without --quality
    #[arg(long, conflicts_with = "critical")]
    pub(crate) check: bool,

    /// Improve the elements after meshing (collapses, flips, edge removal, smoothing) towards
    /// the target dihedral angles, keeping the topology, the labels and the boundary on the
    /// trilinear level sets
    #[arg(long)]
    pub(crate) quality: bool,

    /// Target smallest dihedral angle of --quality, in degrees. Targets above the defaults
    /// (15 and 155) are reached in stages of at most 2.5 degrees, each undone if it leaves the
    /// worst element worse; they take longer, coarsen the mesh and may move the volume more
    #[arg(long, value_name = "DEG", default_value_t = 15.0, allow_hyphen_values = true, value_parser = parse_min_angle, requires = "quality")]
    pub(crate) min_angle: f64,

    /// Target largest dihedral angle of --quality, in degrees
    #[arg(long, value_name = "DEG", default_value_t = 155.0, allow_hyphen_values = true, value_parser = parse_max_angle, requires = "quality")]
    pub(crate) max_angle: f64,

    /// Time budget of --quality in seconds: the pass stops when it runs out (the mesh is valid
    /// then, but how far it got depends on the machine)
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true, value_parser = parse_seconds, requires = "quality")]
    pub(crate) quality_time: Option<f64>,

    /// With --quality, merge two boundary nodes only along an edge shorter than R times the
    /// mean edge length at the node removed, or `inf` for no limit. The limit keeps thin
    /// layers such as shells finer, so their elements stay better shaped; without it convex
    /// boundaries get coarser
    #[arg(long, value_name = "R", default_value = "3", allow_hyphen_values = true, value_parser = parse_ratio, requires = "quality")]
    pub(crate) boundary_collapse_ratio: f64,

    /// With --quality, split a boundary edge whose chord sags from the level set by more than
    /// S times its length, putting the new node on the level set (where no element gets worse
    /// than the target), or `inf` for never. Nodes on a curved level set inscribe the surface
    /// in it: thin tubes lose volume without the splits
    #[arg(long, value_name = "S", default_value = "0.03", allow_hyphen_values = true, value_parser = parse_ratio, requires = "quality")]
    pub(crate) split_sag: f64,

    /// Mesh a generated sample (two vessels a third of a voxel apart) with the interval
    /// [0.5, inf) and show what the decomposition preserves
    #[arg(long, conflicts_with = "input")]
    pub(crate) demo: bool,

    /// Memory limit, e.g. 8G or 512M: runs whose estimate exceeds it stop before the work,
    /// and allocations beyond it end the run with an error [default: the available memory,
    /// for the estimates only]
    #[arg(long, value_name = "SIZE", env = "TPTD_MEMORY_LIMIT", allow_hyphen_values = true, value_parser = parse_memory)]
    pub(crate) memory_limit: Option<u64>,

    /// Print nothing on stdout and no progress bar (warnings and errors still go to stderr)
    #[arg(short, long)]
    pub(crate) quiet: bool,

    /// Instead of meshing, list the critical points and critical regions of the trilinear
    /// field (values where the topology of {f >= w} or {f <= w} changes), with persistence
    #[arg(long, conflicts_with_all = ["output", "demo", "quality"])]
    pub(crate) critical: bool,

    /// With --critical or --inspect: also write the points, or one object per mesh, as a
    /// JSON array to this file
    #[arg(long, value_name = "FILE.json")]
    pub(crate) json: Option<PathBuf>,

    /// Instead of meshing, inspect tetrahedral meshes (.msh, .inp, .vtu, .vtk, Medit .mesh,
    /// TetGen .node/.ele) side by side: counts, volume, dihedral angles, element quality, and the
    /// checker's verdict (conformity, orientation, closed manifold boundary, embedding, Betti
    /// numbers); with --volume, also against the trilinear interval of that volume
    #[arg(long, value_name = "MESH", num_args = 1.., conflicts_with_all = ["output", "demo", "critical", "quality"])]
    pub(crate) inspect: Vec<PathBuf>,

    /// With --inspect: the volume the meshes model (with --alpha and/or --beta): the reference
    /// Betti numbers and volume of the trilinear interval, and the boundary's distance to the
    /// level sets
    #[arg(long, value_name = "VOLUME")]
    pub(crate) volume: Option<PathBuf>,

    /// With --critical: write the contour spectrum (Betti numbers of {f >= w} between
    /// consecutive critical values) as CSV to this file (volumes up to about 10^6 cells)
    #[arg(long, value_name = "FILE.csv", requires = "critical")]
    pub(crate) spectrum: Option<PathBuf>,

    /// With --critical: write a transfer function built from the (filtered) critical values
    /// (“Exploring scalar fields using critical isovalues” §5) as a ParaView colour-map/opacity preset (.json) or as CSV (.csv)
    #[arg(long, value_name = "FILE.json|FILE.csv", requires = "critical")]
    pub(crate) transfer: Option<PathBuf>,

    /// With --transfer: `intervals` (a band of hues per interval between critical values,
    /// opacity hats at them) or `details` (constant except near critical values)
    #[arg(
        long,
        value_enum,
        value_name = "DESIGN",
        default_value = "intervals",
        requires = "transfer"
    )]
    pub(crate) transfer_design: TransferDesignArg,

    /// With --transfer: width (in data units) of the opacity elevations and hue descents
    /// around each critical value; closer critical values are dropped [default: 2% of the
    /// data range]
    #[arg(long, value_name = "W", requires = "transfer", allow_hyphen_values = true, value_parser = parse_nonnegative)]
    pub(crate) transfer_width: Option<f64>,

    /// With --critical: compute the persistence of each point (a union-find over the whole
    /// grid; implied by --min-persistence)
    #[arg(long, requires = "critical")]
    pub(crate) persistence: bool,

    /// With --critical: hide points whose persistence is below P (and those without one)
    #[arg(long, value_name = "P", requires = "critical", allow_hyphen_values = true, value_parser = parse_nonnegative)]
    pub(crate) min_persistence: Option<f64>,

    /// With --critical: hide points with a value below V
    #[arg(long, value_name = "V", allow_hyphen_values = true, requires = "critical", value_parser = parse_bound)]
    pub(crate) min_value: Option<f64>,

    /// With --critical: hide points with a value above V
    #[arg(long, value_name = "V", allow_hyphen_values = true, requires = "critical", value_parser = parse_bound)]
    pub(crate) max_value: Option<f64>,

    /// With --critical: show only these kinds (comma-separated: minimum, maximum, saddle,
    /// face_saddle, body_saddle, region_minimum, region_maximum, region_saddle)
    #[arg(long, value_name = "KINDS", requires = "critical", value_parser = parse_kinds)]
    pub(crate) kind: Option<Kinds>,

    /// Tolerance of the check that --alpha/--beta are not (near) a critical value
    /// [default: 1e-5 of the data range]
    #[arg(long, value_name = "T", allow_hyphen_values = true, value_parser = parse_nonnegative)]
    pub(crate) critical_tol: Option<f64>,

    /// Skip the check of --alpha/--beta against the critical values before meshing
    #[arg(long)]
    pub(crate) no_critical_check: bool,
}

/// `--transfer-design` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum TransferDesignArg {
    Intervals,
    Details,
}

impl TransferDesignArg {
    /// The library's design of this value.
    pub(crate) fn design(self) -> TransferDesign {
        match self {
            TransferDesignArg::Intervals => TransferDesign::Intervals,
            TransferDesignArg::Details => TransferDesign::Details,
        }
    }
}

/// A parsed `--kind` list.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Kinds(pub(crate) Vec<CriticalKind>);

/// Parses `--kind`: comma-separated kind names.
fn parse_kinds(s: &str) -> Result<Kinds, String> {
    s.split(',')
        .map(|k| {
            CriticalKind::from_name(k.trim()).ok_or_else(|| {
                let names: Vec<&str> = CriticalKind::ALL.iter().map(|k| k.name()).collect();
                format!("unknown kind '{}' (one of {})", k.trim(), names.join(", "))
            })
        })
        .collect::<Result<Vec<_>, _>>()
        .map(Kinds)
}

/// Parses a finite number >= 0.
fn parse_nonnegative(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v >= 0.0 && v.is_finite() => Ok(v),
        _ => Err(format!("expected a finite number >= 0, got '{s}'")),
    }
}

/// `--method` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum MethodArg {
    Ctd,
    Tptd,
    Std,
    Six,
    Five,
}

impl MethodArg {
    /// The decomposition method of this value.
    pub(crate) fn method(self) -> Method {
        match self {
            MethodArg::Ctd => Method::Ctd,
            MethodArg::Tptd => Method::Tptd,
            MethodArg::Std => Method::Std,
            MethodArg::Six => Method::Six,
            MethodArg::Five => Method::Five,
        }
    }
}

/// `--msh-version` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum MshVersionArg {
    #[value(name = "4.1")]
    V41,
    #[value(name = "2.2")]
    V22,
    #[value(name = "4.1-binary")]
    V41Binary,
}

/// Parses `--min-angle`: a smallest dihedral angle a tetrahedron can have (below 70.5°).
fn parse_min_angle(s: &str) -> Result<f64, String> {
    parse_angle(s, 0.0, 70.0)
}

/// Parses `--max-angle`: a largest dihedral angle a tetrahedron can have (above 70.5°).
fn parse_max_angle(s: &str) -> Result<f64, String> {
    parse_angle(s, 71.0, 180.0)
}

fn parse_angle(s: &str, lo: f64, hi: f64) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(a) if a > lo && a < hi => Ok(a),
        _ => Err(format!(
            "expected an angle in degrees between {lo} and {hi}, got '{s}'"
        )),
    }
}

/// Parses `--boundary-collapse-ratio` and `--split-sag`: a positive number, or `inf` (no
/// limit, never).
fn parse_ratio(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(r) if r > 0.0 && !r.is_nan() => Ok(r),
        _ => Err(format!("expected a positive ratio or inf, got '{s}'")),
    }
}

/// Parses `--quality-time`: a positive number of seconds.
fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t > 0.0 && t.is_finite() => Ok(t),
        _ => Err(format!("expected a positive number of seconds, got '{s}'")),
    }
}

/// `--vtu-encoding` values.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub(crate) enum VtuEncodingArg {
    Base64,
    Zlib,
    Raw,
}

impl VtuEncodingArg {
    /// The `.vtu` encoding of this value.
    pub(crate) fn encoding(self) -> VtuEncoding {
        match self {
            VtuEncodingArg::Base64 => VtuEncoding::Base64,
            VtuEncodingArg::Zlib => VtuEncoding::Zlib,
            VtuEncodingArg::Raw => VtuEncoding::Raw,
        }
    }
}

/// A parsed `--spacing`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Spacing(pub(crate) [f64; 3]);

impl MshVersionArg {
    /// The `.msh` version of this value.
    pub(crate) fn version(self) -> MshVersion {
        match self {
            MshVersionArg::V41 => MshVersion::V41,
            MshVersionArg::V22 => MshVersion::V22,
            MshVersionArg::V41Binary => MshVersion::V41Binary,
        }
    }
}

/// Parses `--memory-limit`: a size such as `512M`, `8G` or a number of bytes.
fn parse_memory(s: &str) -> Result<u64, String> {
    tptd::memory::parse_size(s)
        .ok_or_else(|| format!("'{s}' is not a size (use e.g. 512M, 8G or a number of bytes)"))
}

/// Parses an interval bound: a number, `inf`/`-inf`; NaN is rejected.
fn parse_bound(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number (use e.g. 0.5, -1e3, inf or -inf)"))?;
    if v.is_nan() {
        return Err("NaN is not a valid bound".into());
    }
    Ok(v)
}

/// Parses `sx,sy,sz` (three finite positive numbers).
fn parse_spacing(s: &str) -> Result<Spacing, String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!(
            "'{s}' must be three comma-separated numbers sx,sy,sz"
        ));
    }
    let mut out = [0.0; 3];
    for (o, p) in out.iter_mut().zip(&parts) {
        let v: f64 = p
            .trim()
            .parse()
            .map_err(|_| format!("'{}' is not a number", p.trim()))?;
        if !v.is_finite() || v <= 0.0 {
            return Err(format!(
                "spacing '{}' must be finite and positive",
                p.trim()
            ));
        }
        *o = v;
    }
    Ok(Spacing(out))
}

/// Parses the command line and refuses options that do nothing in the chosen mode
/// ([`crate::applies`]). `--help` and `--version` print as clap does (stdout, exit 0);
/// a usage error prints one line `tptd-mesh: error: … (see tptd-mesh --help)` on stderr and
/// exits with status 2.
pub(crate) fn parse_or_exit() -> Cli {
    use clap::error::ErrorKind;
    use clap::{CommandFactory, FromArgMatches};
    let parsed = Cli::command().try_get_matches().and_then(|m| {
        let cli = Cli::from_arg_matches(&m)?;
        crate::applies::check(&cli, &m)
            .map_err(|msg| Cli::command().error(ErrorKind::ArgumentConflict, msg))?;
        Ok(cli)
    });
    let e = match parsed {
        Ok(cli) => return cli,
        Err(e) => e,
    };
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
        e.exit();
    }
    let text = e.render().to_string();
    let msg: Vec<&str> = text
        .lines()
        .map(str::trim)
        .take_while(|l| !l.is_empty())
        .collect();
    let msg = msg.join(" ");
    let msg = msg.strip_prefix("error: ").unwrap_or(&msg);
    eprintln!("tptd-mesh: error: {msg} (see tptd-mesh --help)");
    std::process::exit(2);
}
