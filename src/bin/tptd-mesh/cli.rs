//! Command-line arguments: the clap definition and the value parsers.

use std::path::PathBuf;

use clap::{Parser, ValueEnum};
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
    /// Input volume (.npy, .nrrd, .nhdr, .nii, .nii.gz, .mhd, .mha)
    #[arg(value_name = "INPUT", required_unless_present = "demo")]
    pub(crate) input: Option<PathBuf>,

    /// Output mesh; the format follows the extension: .msh (Gmsh), .inp (Abaqus/CalculiX),
    /// .vtu (VTK) [default with --demo: tptd-demo.vtu]
    #[arg(short, long, value_name = "OUT", required_unless_present = "demo")]
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
    #[arg(short = 'j', long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub(crate) threads: Option<u32>,

    /// Gmsh file format version for .msh output
    #[arg(long, value_enum, value_name = "VERSION", default_value_t = MshVersionArg::V41)]
    pub(crate) msh_version: MshVersionArg,

    /// Data encoding of .vtu output: base64 (read by meshio, VTK and ParaView), zlib
    /// (compressed, as VTK writes; smallest, slowest) or raw (fastest; meshio cannot read it)
    #[arg(long, value_enum, value_name = "ENCODING", default_value_t = VtuEncodingArg::Base64)]
    pub(crate) vtu_encoding: VtuEncodingArg,

    /// Override the grid spacing (physical size of a voxel, in the file's units, e.g. mm),
    /// e.g. 0.5,0.5,1.2
    #[arg(long, value_name = "SX,SY,SZ", value_parser = parse_spacing)]
    pub(crate) spacing: Option<Spacing>,

    /// Skip the Betti numbers and dihedral angles
    #[arg(long)]
    pub(crate) no_analysis: bool,

    /// Improve the elements after meshing (collapses, flips, smoothing) towards the target
    /// dihedral angles, keeping the topology, the labels and the boundary on the trilinear
    /// level sets
    #[arg(long)]
    pub(crate) quality: bool,

    /// Target smallest dihedral angle of --quality, in degrees
    #[arg(long, value_name = "DEG", default_value_t = 15.0, value_parser = parse_min_angle)]
    pub(crate) min_angle: f64,

    /// Target largest dihedral angle of --quality, in degrees
    #[arg(long, value_name = "DEG", default_value_t = 155.0, value_parser = parse_max_angle)]
    pub(crate) max_angle: f64,

    /// Time budget of --quality in seconds: the pass stops when it runs out (the mesh is valid
    /// then, but how far it got depends on the machine)
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub(crate) quality_time: Option<f64>,

    /// Mesh a generated sample (two vessels a third of a voxel apart) with the interval
    /// [0.5, inf) and show what the decomposition preserves
    #[arg(long, conflicts_with = "input")]
    pub(crate) demo: bool,

    /// Memory limit, e.g. 8G or 512M: runs whose estimate exceeds it stop before the work,
    /// and allocations beyond it end the run with an error [default: the available memory,
    /// for the estimates only]
    #[arg(long, value_name = "SIZE", env = "TPTD_MEMORY_LIMIT", value_parser = parse_memory)]
    pub(crate) memory_limit: Option<u64>,

    /// Print nothing on stdout and no progress bar (warnings and errors still go to stderr)
    #[arg(short, long)]
    pub(crate) quiet: bool,
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

/// Parses the command line. `--help` and `--version` print as clap does (stdout, exit 0);
/// a usage error prints one line `tptd-mesh: error: … (see tptd-mesh --help)` on stderr and
/// exits with status 2.
pub(crate) fn parse_or_exit() -> Cli {
    let e = match Cli::try_parse() {
        Ok(cli) => return cli,
        Err(e) => e,
    };
    use clap::error::ErrorKind;
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
