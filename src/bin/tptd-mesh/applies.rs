//! Options that would do nothing are refused, not ignored: an option of `--critical` while
//! meshing, a meshing option with `--critical`, an option of another output format or
//! another kind of input. Each is a usage error (exit 2) naming the option, as clap's own
//! `requires` gives for the quality knobs without `--quality`. The output's extension, the
//! `--transfer` file's extension and `-j` are checked here too, so that they are usage
//! errors as well.

use std::path::{Path, PathBuf};

use clap::parser::ValueSource;
use clap::ArgMatches;
use tptd::io::{is_curvilinear, is_plot3d, MeshFormat, SurfaceFormat, TransferFormat};

use crate::cli::Cli;

/// Options (clap ids) that only `--critical` uses (`--json` also applies with `--inspect`).
const CRITICAL_ONLY: [&str; 9] = [
    "spectrum",
    "transfer",
    "transfer_design",
    "transfer_width",
    "persistence",
    "min_persistence",
    "min_value",
    "max_value",
    "kind",
];

/// Options (clap ids) that only meshing uses (`--critical` reads the volume and lists its
/// critical points; `-o` and `--quality` conflict with it in clap already).
const MESH_ONLY: [&str; 13] = [
    "alpha",
    "beta",
    "method",
    "report",
    "msh_version",
    "vtu_encoding",
    "field",
    "function",
    "caps",
    "ascii",
    "no_analysis",
    "critical_tol",
    "no_critical_check",
];

/// Whether option `id` is on the command line (not a default).
fn given(m: &ArgMatches, id: &str) -> bool {
    m.value_source(id) == Some(ValueSource::CommandLine)
}

/// The option as spelled on the command line.
fn flag(id: &str) -> String {
    format!("--{}", id.replace('_', "-"))
}

/// The first of `ids` on the command line.
fn first_given<'a>(m: &ArgMatches, ids: &[&'a str]) -> Option<&'a str> {
    ids.iter().copied().find(|id| given(m, id))
}

/// Checks that every option given applies to the mode, the output and the input, that the
/// output's format is known and that `-j` is within the machine's limit.
///
/// # Errors
/// One line naming the first option that does nothing (or the output, or `-j`).
pub(crate) fn check(cli: &Cli, m: &ArgMatches) -> Result<(), String> {
    crate::run::check_threads(cli.threads).map_err(|e| e.to_string())?;
    if !cli.inspect.is_empty() {
        return check_inspect(cli, m);
    }
    if given(m, "volume") {
        return Err("--volume applies only with --inspect".into());
    }
    if given(m, "json") && !cli.critical {
        return Err("--json applies only with --critical or --inspect".into());
    }
    if cli.critical {
        if let Some(id) = first_given(m, &MESH_ONLY) {
            return Err(format!(
                "{} does not apply with --critical (it lists the critical points and meshes \
                 nothing)",
                flag(id)
            ));
        }
        return check_transfer(cli.transfer.as_deref());
    }
    if let Some(id) = first_given(m, &CRITICAL_ONLY) {
        return Err(format!("{} applies only with --critical", flag(id)));
    }
    let output = match &cli.output {
        Some(p) => p.clone(),
        None => PathBuf::from(crate::run::DEMO_OUTPUT),
    };
    check_output(m, &output)?;
    check_input(cli, m)?;
    if cli.no_critical_check && given(m, "critical_tol") {
        return Err("--critical-tol does nothing with --no-critical-check".into());
    }
    Ok(())
}

/// Options (clap ids) that apply with `--inspect`.
const INSPECT_OPTIONS: [&str; 9] = [
    "inspect",
    "volume",
    "alpha",
    "beta",
    "spacing",
    "json",
    "threads",
    "quiet",
    "memory_limit",
];

/// With `--inspect`: only its options, the interval and `--spacing` only with `--volume`,
/// and with `--volume` an interval.
fn check_inspect(cli: &Cli, m: &ArgMatches) -> Result<(), String> {
    if cli.input.is_some() {
        return Err(
            "--inspect takes the meshes, not an INPUT volume: give the volume with --volume".into(),
        );
    }
    let command = <Cli as clap::CommandFactory>::command();
    let other = command
        .get_arguments()
        .map(|a| a.get_id().as_str())
        .find(|id| given(m, id) && !INSPECT_OPTIONS.contains(id));
    if let Some(id) = other {
        return Err(format!(
            "{} does not apply with --inspect (it inspects meshes and meshes nothing)",
            flag(id)
        ));
    }
    if cli.volume.is_none() {
        if let Some(id) = first_given(m, &["alpha", "beta", "spacing"]) {
            return Err(format!(
                "{} applies with --inspect only together with --volume",
                flag(id)
            ));
        }
    } else if cli.alpha.is_none() && cli.beta.is_none() {
        return Err("--volume needs the interval: --alpha A and/or --beta B".into());
    }
    Ok(())
}

/// The format of `--transfer FILE` is known from its extension (a directory is left to the
/// run's check that the outputs can be written, which names it as one).
fn check_transfer(transfer: Option<&Path>) -> Result<(), String> {
    match transfer {
        Some(path) if TransferFormat::from_path(path).is_none() && !path.is_dir() => Err(format!(
            "--transfer {}: unknown transfer-function format; use .json (ParaView preset) or .csv",
            path.display()
        )),
        _ => Ok(()),
    }
}

/// The output's format is known and the options of other formats are not given.
fn check_output(m: &ArgMatches, output: &Path) -> Result<(), String> {
    let surface = SurfaceFormat::from_path(output);
    let mesh = match surface {
        Some(_) => None,
        None => Some(MeshFormat::from_path(output).map_err(|e| {
            // the writer's own message for an unknown extension
            crate::error::write_error(e).to_string()
        })?),
    };
    let name = output.display();
    let refuse =
        |id: &str, only: &str| Err(format!("{} applies only to {only}, not {name}", flag(id)));
    if given(m, "msh_version") && mesh != Some(MeshFormat::Msh) {
        return refuse("msh_version", ".msh output");
    }
    if given(m, "vtu_encoding") && mesh != Some(MeshFormat::Vtu) {
        return refuse("vtu_encoding", ".vtu output");
    }
    if given(m, "caps") && surface.is_none() {
        return refuse("caps", "isosurface output (.obj, .ply, .stl)");
    }
    if given(m, "ascii") && !matches!(surface, Some(SurfaceFormat::Ply | SurfaceFormat::Stl)) {
        return refuse("ascii", ".ply and .stl output (.obj is always text)");
    }
    Ok(())
}

/// The options of curvilinear inputs are given with one, `--spacing` without one.
fn check_input(cli: &Cli, m: &ArgMatches) -> Result<(), String> {
    let input = cli.input.as_deref();
    let name = input.map_or("the demo volume".to_string(), |p| p.display().to_string());
    let curvilinear = input.is_some_and(is_curvilinear);
    let plot3d = input.is_some_and(is_plot3d);
    if given(m, "field") && !curvilinear {
        return Err(format!(
            "--field applies only to a curvilinear grid input (.vts, .xyz), not {name}"
        ));
    }
    if given(m, "function") && !plot3d {
        return Err(format!(
            "--function applies only to a Plot3D grid input (.xyz), not {name}"
        ));
    }
    if given(m, "spacing") && curvilinear {
        return Err(format!(
            "--spacing does not apply to a curvilinear grid ({name}: its points give the \
             geometry)"
        ));
    }
    Ok(())
}
