//! Command-line arguments: the clap definition (values parsed by
//! [`tptd::pipeline::values`]), the flag of each of the library's parameters, and the
//! library's check that every option given applies ([`tptd::pipeline::check_applies`]).

use std::path::PathBuf;
use std::sync::OnceLock;

use clap::parser::ValueSource;
use clap::{ArgMatches, Parser, ValueEnum};
use tptd::critical::{CriticalKind, TransferDesign};
use tptd::io::msh::MshVersion;
use tptd::io::vtu::VtuEncoding;
use tptd::pipeline::values::{bound, max_angle, memory_size, min_angle, nonnegative, ratio};
use tptd::pipeline::values::{kinds, levels, names, positive, seconds, spacing};
use tptd::pipeline::{check_applies, Given, Mode, Param, ParamNames};
use tptd::Method;

/// Mesh the interval volume {alpha <= f <= beta} of a 3-D scalar grid into tetrahedra, with
/// the topology of the trilinear interpolant.
///
/// Grid values equal to a bound count as outside the interval. Lengths and volumes are in the
/// file's units (millimetres for NIfTI and most NRRD and MetaImage images; voxels for .npy,
/// whose spacing is 1 unless --spacing says otherwise).
///
/// A closed surface (.obj, .stl, .ply) is meshed as the solid it bounds: its signed distance d
/// (negative inside, by the winding number; in the surface's units) is sampled on a grid
/// around it and {d <= 0} is meshed; --beta B offsets the surface outwards by B (inwards if
/// negative), --alpha A < B keeps only a shell {A <= d <= B}.
#[derive(Parser, Debug)]
#[command(name = "tptd-mesh", version)]
pub(crate) struct Cli {
    /// Input volume (.npy, .nrrd, .nhdr, .nii, .nii.gz, .mhd, .mha), a curvilinear grid (.vts,
    /// or a Plot3D .xyz with its .q or .f file), or a closed surface (.obj, .stl, .ply)
    #[arg(value_name = "INPUT", required_unless_present_any = ["demo", "inspect"])]
    pub(crate) input: Option<PathBuf>,

    /// Output; its extension gives the format: .msh (Gmsh), .inp (Abaqus/CalculiX), .vtu (VTK)
    /// for tetrahedra; .obj, .ply, .stl for the level sets f = alpha and f = beta (with
    /// --levels every level; normals towards increasing f) [default with --demo:
    /// tptd-demo.vtu]
    #[arg(short, long, value_name = "OUT", required_unless_present_any = ["demo", "critical", "inspect"])]
    pub(crate) output: Option<PathBuf>,

    /// Lower bound of the interval [default: -inf; --alpha and/or --beta is required, except
    /// with a surface input]
    #[arg(long, value_name = "A", allow_hyphen_values = true, value_parser = bound)]
    pub(crate) alpha: Option<f64>,

    /// Upper bound of the interval [default: inf; with a surface input 0, the surface]
    #[arg(long, value_name = "B", allow_hyphen_values = true, value_parser = bound)]
    pub(crate) beta: Option<f64>,

    /// Several levels L1,L2,...,Ln (increasing, 2 to 16; -inf and inf at the ends): mesh the
    /// regions [L1, L2], ..., [Ln-1, Ln] in one pass as one conforming mesh, each tet tagged
    /// with its region and the levels between regions kept as interfaces; instead of
    /// --alpha/--beta
    #[arg(long, value_name = "L1,L2,...", allow_hyphen_values = true, value_parser = |s: &str| levels(s).map(Levels))]
    pub(crate) levels: Option<Levels>,

    /// With --levels: the regions' names, one per region (a letter, then letters, digits and
    /// _) [default: region1,region2,...]
    #[arg(long, value_name = "A,B,...", value_parser = |s: &str| names(s).map(Names))]
    pub(crate) region_names: Option<Names>,

    /// Cell decomposition: ctd and tptd keep the trilinear topology (ctd with fewer tets); std
    /// keeps it except in cells both bounds cross; six and five do not
    #[arg(long, value_enum, default_value_t = MethodArg::Ctd)]
    pub(crate) method: MethodArg,

    /// Also write a JSON report of the run to this file
    #[arg(long, value_name = "FILE.json")]
    pub(crate) report: Option<PathBuf>,

    /// Worker threads [default: all cores]
    #[arg(short = 'j', long, value_name = "N", allow_hyphen_values = true, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub(crate) threads: Option<u32>,

    /// .msh format: 4.1 (ASCII), 2.2 (ASCII) or 4.1-binary (faster to write and read)
    #[arg(long, value_enum, value_name = "VERSION", default_value_t = MshVersionArg::V41)]
    pub(crate) msh_version: MshVersionArg,

    /// .vtu data encoding: base64 (meshio, VTK, ParaView), zlib (smallest, slowest) or raw
    /// (fastest; meshio cannot read it)
    #[arg(long, value_enum, value_name = "ENCODING", default_value_t = VtuEncodingArg::Base64)]
    pub(crate) vtu_encoding: VtuEncodingArg,

    /// Grid spacing instead of the file's (a voxel's size in the file's units), e.g. 0.5,0.5,1.2
    #[arg(long, value_name = "SX,SY,SZ", allow_hyphen_values = true, value_parser = |s: &str| spacing(s).map(Spacing))]
    pub(crate) spacing: Option<Spacing>,

    /// Surface input: voxels of the signed-distance grid along the longest side of the
    /// surface's box, which is padded by at least 3 voxels [default: 64]
    #[arg(long, value_name = "N", allow_hyphen_values = true, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub(crate) resolution: Option<u32>,

    /// Surface input: width of the signed-distance grid's cubic voxels, in the surface's units
    /// (instead of --resolution)
    #[arg(long, value_name = "H", allow_hyphen_values = true, value_parser = positive)]
    pub(crate) voxel_size: Option<f64>,

    /// Curvilinear input: the scalar (.vts) or Plot3D variable (a name such as density, or a
    /// 1-based number) to mesh [default: the first]
    #[arg(long, value_name = "NAME")]
    pub(crate) field: Option<String>,

    /// Plot3D input: the function file (.q or .f) [default: the grid's name with .q, else .f]
    #[arg(long, value_name = "FILE")]
    pub(crate) function: Option<PathBuf>,

    /// Surface output: also the triangles on the grid box that close the surface
    #[arg(long)]
    pub(crate) caps: bool,

    /// Surface output: ASCII instead of binary .ply / .stl
    #[arg(long)]
    pub(crate) ascii: bool,

    /// Skip the Betti numbers and dihedral angles
    #[arg(long)]
    pub(crate) no_analysis: bool,

    /// Check the mesh before writing it (a failure writes nothing; holds the mesh in memory):
    /// conforming, positive tets, a closed manifold boundary not meeting itself, winding number
    /// 1 at sampled tets, alpha/beta triangles within half a voxel of their trilinear level sets
    /// with ctd and tptd, a cell's diagonal with std, six and five (parameter space on
    /// curvilinear grids)
    #[arg(long, conflicts_with = "critical")]
    pub(crate) check: bool,

    /// Improve the elements after meshing (collapses, flips, edge removal, smoothing) towards
    /// the target angles, keeping the topology, the labels and the boundary on the level sets
    /// (with --levels: every region's topology and volume, interface nodes on their levels)
    #[arg(long)]
    pub(crate) quality: bool,

    /// --quality's target smallest dihedral angle (degrees); targets above the defaults (15,
    /// 155) are climbed in stages of at most 2.5°, each undone if it makes the worst element
    /// worse: slower, coarser, may move the volume more
    #[arg(long, value_name = "DEG", default_value_t = 15.0, allow_hyphen_values = true, value_parser = min_angle, requires = "quality")]
    pub(crate) min_angle: f64,

    /// --quality's target largest dihedral angle (degrees)
    #[arg(long, value_name = "DEG", default_value_t = 155.0, allow_hyphen_values = true, value_parser = max_angle, requires = "quality")]
    pub(crate) max_angle: f64,

    /// --quality's time budget in seconds (the mesh is valid when it runs out; how far the pass
    /// got depends on the machine)
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true, value_parser = seconds, requires = "quality")]
    pub(crate) quality_time: Option<f64>,

    /// --quality merges two boundary nodes only along an edge shorter than R times the mean edge
    /// length at the node removed (inf: no limit); keeps thin layers finer and better shaped
    #[arg(long, value_name = "R", default_value = "3", allow_hyphen_values = true, value_parser = ratio, requires = "quality")]
    pub(crate) boundary_collapse_ratio: f64,

    /// --quality splits a boundary edge whose chord sags from the level set by more than S times
    /// its length, at a node on the level set (inf: never); thin tubes keep their volume
    #[arg(long, value_name = "S", default_value = "0.03", allow_hyphen_values = true, value_parser = ratio, requires = "quality")]
    pub(crate) split_sag: f64,

    /// Grade the interior: elements deep inside the domain grow to mean edge length H (file
    /// units): cubes of the power of two cells nearest H (going up from 1.5 times one, so
    /// within a third of H) coned from their centres, while every cell a level passes through
    /// keeps its fine tets; the boundary, regions, topology and volume do not change (holds
    /// the mesh in memory; not with a curvilinear grid)
    #[arg(long, value_name = "H", allow_hyphen_values = true, value_parser = positive)]
    pub(crate) max_edge: Option<f64>,

    /// How fast --max-edge lets sizes grow away from the surfaces: a cube of side s cells
    /// lies at least (s - 1)/(G - 1) cells from any cell a level passes through (above 2,
    /// the 2:1 balance between cubes keeps them that far already)
    #[arg(long, value_name = "G", default_value = "1.5", allow_hyphen_values = true, value_parser = positive, requires = "max_edge")]
    pub(crate) grading: f64,

    /// Mesh a generated sample (two vessels a third of a voxel apart), interval [0.5, inf),
    /// and show what the decomposition preserves
    #[arg(long, conflicts_with = "input")]
    pub(crate) demo: bool,

    /// Memory limit, e.g. 8G or 512M: runs estimated above it stop before the work, and
    /// allocations beyond it end the run with an error [default: the available memory, for
    /// the estimates only]
    #[arg(long, value_name = "SIZE", env = "TPTD_MEMORY_LIMIT", allow_hyphen_values = true, value_parser = memory_size)]
    pub(crate) memory_limit: Option<u64>,

    /// Nothing on stdout and no progress bar (warnings and errors still go to stderr)
    #[arg(short, long)]
    pub(crate) quiet: bool,

    /// Instead of meshing, list the critical points and regions of the trilinear field (where
    /// the topology of {f >= w} or {f <= w} changes), with persistence
    #[arg(long, conflicts_with_all = ["output", "demo", "quality"])]
    pub(crate) critical: bool,

    /// With --critical or --inspect: also write the points, or one object per mesh, as JSON
    #[arg(long, value_name = "FILE.json")]
    pub(crate) json: Option<PathBuf>,

    /// Instead of meshing, inspect tetrahedral meshes (.msh, .inp, .vtu, .vtk, Medit .mesh,
    /// TetGen .node/.ele) side by side: counts, volume, dihedral angles, quality, the checker's
    /// verdict (conformity, orientation, closed manifold boundary, embedding, Betti numbers)
    #[arg(long, value_name = "MESH", num_args = 1.., conflicts_with_all = ["output", "demo", "critical", "quality"])]
    pub(crate) inspect: Vec<PathBuf>,

    /// With --inspect and --alpha/--beta: the volume the meshes model, for the trilinear
    /// interval's Betti numbers and volume and the boundary's distance to the level sets
    #[arg(long, value_name = "VOLUME")]
    pub(crate) volume: Option<PathBuf>,

    /// With --critical: the contour spectrum (Betti numbers of {f >= w} between consecutive
    /// critical values) as CSV (volumes up to about 10^6 cells)
    #[arg(long, value_name = "FILE.csv", requires = "critical")]
    pub(crate) spectrum: Option<PathBuf>,

    /// With --critical: a transfer function from the (filtered) critical values (“Exploring
    /// scalar fields using critical isovalues” §5), a ParaView preset (.json) or CSV (.csv)
    #[arg(long, value_name = "FILE.json|FILE.csv", requires = "critical")]
    pub(crate) transfer: Option<PathBuf>,

    /// With --transfer: intervals (a band of hues per interval between critical values,
    /// opacity hats at them) or details (constant except near critical values)
    #[arg(
        long,
        value_enum,
        value_name = "DESIGN",
        default_value = "intervals",
        requires = "transfer"
    )]
    pub(crate) transfer_design: TransferDesignArg,

    /// With --transfer: width (data units) of the opacity and hue features at each critical
    /// value; closer critical values are dropped [default: 2% of the data range]
    #[arg(long, value_name = "W", requires = "transfer", allow_hyphen_values = true, value_parser = nonnegative)]
    pub(crate) transfer_width: Option<f64>,

    /// With --critical: each point's persistence (a union-find over the grid; implied by
    /// --min-persistence)
    #[arg(long, requires = "critical")]
    pub(crate) persistence: bool,

    /// With --critical: hide points whose persistence is below P (or unknown)
    #[arg(long, value_name = "P", requires = "critical", allow_hyphen_values = true, value_parser = nonnegative)]
    pub(crate) min_persistence: Option<f64>,

    /// With --critical: hide points with a value below V
    #[arg(long, value_name = "V", allow_hyphen_values = true, requires = "critical", value_parser = bound)]
    pub(crate) min_value: Option<f64>,

    /// With --critical: hide points with a value above V
    #[arg(long, value_name = "V", allow_hyphen_values = true, requires = "critical", value_parser = bound)]
    pub(crate) max_value: Option<f64>,

    /// With --critical: only these kinds (comma-separated: minimum, maximum, saddle,
    /// face_saddle, body_saddle, region_minimum, region_maximum, region_saddle)
    #[arg(long, value_name = "KINDS", requires = "critical", value_parser = |s: &str| kinds(s).map(Kinds))]
    pub(crate) kind: Option<Kinds>,

    /// Tolerance of the check that --alpha/--beta are not (near) a critical value [default:
    /// 1e-5 of the data range]
    #[arg(long, value_name = "T", allow_hyphen_values = true, value_parser = nonnegative)]
    pub(crate) critical_tol: Option<f64>,

    /// Skip the check of --alpha/--beta against the critical values before meshing
    #[arg(long)]
    pub(crate) no_critical_check: bool,
}

/// A `--spacing`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Spacing(pub(crate) [f64; 3]);

/// A `--levels` list.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Levels(pub(crate) Vec<f64>);

/// A `--region-names` list.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Names(pub(crate) Vec<String>);

/// A `--kind` list.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Kinds(pub(crate) Vec<CriticalKind>);

/// An option's values, each with the library's value it stands for (`get`).
macro_rules! values {
    ($(#[$m:meta])* $name:ident -> $lib:ident { $($(#[$vm:meta])* $v:ident => $l:ident),* }) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
        pub(crate) enum $name { $($(#[$vm])* $v),* }
        impl $name {
            /// The library's value.
            pub(crate) fn get(self) -> $lib {
                match self { $($name::$v => $lib::$l),* }
            }
        }
    };
}

values!(/// `--method` values.
    MethodArg -> Method { Ctd => Ctd, Tptd => Tptd, Std => Std, Six => Six, Five => Five });
values!(/// `--msh-version` values.
    MshVersionArg -> MshVersion { #[value(name = "4.1")] V41 => V41,
        #[value(name = "2.2")] V22 => V22, #[value(name = "4.1-binary")] V41Binary => V41Binary });
values!(/// `--vtu-encoding` values.
    VtuEncodingArg -> VtuEncoding { Base64 => Base64, Zlib => Zlib, Raw => Raw });
values!(/// `--transfer-design` values.
    TransferDesignArg -> TransferDesign { Intervals => Intervals, Details => Details });

/// The flag of each parameter: `-o`, `-j`, `--alpha`, … (`INPUT` for the input).
fn flag(p: Param) -> &'static str {
    static FLAGS: OnceLock<Vec<String>> = OnceLock::new();
    let all = FLAGS.get_or_init(|| {
        let flag = |p: Param| match p {
            Param::Input => "INPUT".to_string(),
            Param::Output => "-o".to_string(),
            Param::Threads => "-j".to_string(),
            p => format!("--{}", p.name().replace('_', "-")),
        };
        Param::ALL.into_iter().map(flag).collect()
    });
    &all[Param::ALL.iter().position(|&q| q == p).unwrap_or(0)]
}

/// The library's messages name the parameters by their flags.
pub(crate) const FLAGS: ParamNames = ParamNames(flag);

/// The library's check that every option given applies ([`check_applies`]), in flags.
fn check(cli: &Cli, m: &ArgMatches) -> Result<(), String> {
    let given = |p: &Param| m.value_source(p.name()) == Some(ValueSource::CommandLine);
    let params: Vec<Param> = Param::ALL.into_iter().filter(given).collect();
    let mode = match (cli.inspect.is_empty(), cli.critical) {
        (false, _) => Mode::Inspect,
        (true, true) => Mode::Critical,
        (true, false) => Mode::Mesh,
    };
    let given = Given {
        mode,
        params: &params,
        input: cli.input.as_deref(),
        output: cli.output.as_deref(),
        transfer: cli.transfer.as_deref(),
        threads: cli.threads.map(|n| n as usize),
    };
    check_applies(&given).map_err(|e| e.render(FLAGS))
}

/// Parses the command line and refuses options that do nothing in the chosen mode.
/// `--help` and `--version` print as clap does (stdout, exit 0); a usage error prints one line
/// `tptd-mesh: error: … (see tptd-mesh --help)` on stderr and exits with status 2.
pub(crate) fn parse_or_exit() -> Cli {
    use clap::error::ErrorKind;
    use clap::{CommandFactory, FromArgMatches};
    let parsed = Cli::command().try_get_matches().and_then(|m| {
        let cli = Cli::from_arg_matches(&m)?;
        check(&cli, &m).map_err(|msg| Cli::command().error(ErrorKind::ArgumentConflict, msg))?;
        Ok(cli)
    });
    let e = match parsed {
        Ok(cli) => {
            // spelt before the memory limit is set, so that the limit does not count them
            let _ = flag(Param::Input);
            return cli;
        }
        Err(e) => e,
    };
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
        e.exit();
    }
    let text = e.render().to_string();
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .take_while(|l| !l.is_empty())
        .collect();
    let msg = lines.join(" ");
    let msg = msg.strip_prefix("error: ").unwrap_or(&msg);
    eprintln!("tptd-mesh: error: {msg} (see tptd-mesh --help)");
    std::process::exit(2);
}
