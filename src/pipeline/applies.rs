//! Parameters that would do nothing are refused, not ignored: a parameter of the critical
//! points while meshing, a meshing parameter with the critical points or an inspection, a
//! parameter of another output format or another kind of input. [`check_applies`] takes
//! what a front end was given ([`Given`]) and names the first such parameter in a typed
//! error ([`Inapplicable`]), which a front end renders with its own names
//! ([`Inapplicable::render`]). The output's format, the transfer function's format and the
//! thread count are checked here too, so that they are refused with the rest.

use std::fmt;
use std::path::{Path, PathBuf};

use crate::io::{is_curvilinear, is_plot3d, is_surface, MeshFormat, SurfaceFormat, TransferFormat};

use super::request::{too_many_threads, DEMO_OUTPUT};
use super::{Param, ParamNames, PipelineError};

/// What a run does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Meshes an interval volume ([`super::mesh_file`]).
    Mesh,
    /// Lists the critical points ([`super::critical_file`]).
    Critical,
    /// Inspects meshes ([`super::inspect_files`]).
    Inspect,
}

/// What a front end was given: the mode, the parameters set explicitly (not defaults) and
/// the values the check looks at.
#[derive(Clone, Copy, Debug)]
pub struct Given<'a> {
    /// What the run does.
    pub mode: Mode,
    /// The parameters set explicitly.
    pub params: &'a [Param],
    /// The input volume (`None`: the demo volume, or none with an inspection).
    pub input: Option<&'a Path>,
    /// The output of a meshing run (`None`: the demo's [`DEMO_OUTPUT`]).
    pub output: Option<&'a Path>,
    /// The transfer-function output of a critical-points run.
    pub transfer: Option<&'a Path>,
    /// Worker threads.
    pub threads: Option<usize>,
}

impl Given<'_> {
    fn has(&self, p: Param) -> bool {
        self.params.contains(&p)
    }

    /// The first of `list` given.
    fn first(&self, list: &[Param]) -> Option<Param> {
        list.iter().copied().find(|&p| self.has(p))
    }
}

/// Why a parameter given does not apply (or the output or the thread count is refused).
#[derive(Clone, Debug, PartialEq)]
pub enum Inapplicable {
    /// `param` applies only with `with` (one of them).
    OnlyWith {
        /// The parameter given.
        param: Param,
        /// The modes it applies with.
        with: &'static [Param],
    },
    /// `param` does nothing in `mode` (a mode's parameter), for the reason `why`.
    NotWith {
        /// The parameter given.
        param: Param,
        /// The mode's parameter.
        mode: Param,
        /// What the mode does instead.
        why: &'static str,
    },
    /// An inspection was given an input volume instead of its reference volume.
    InspectInput,
    /// `param` applies to an inspection only with a reference volume.
    NeedsVolume(Param),
    /// A reference volume was given without an interval.
    VolumeNeedsInterval,
    /// `param` does nothing when `other` is given.
    NothingWith {
        /// The parameter given.
        param: Param,
        /// The parameter that makes it do nothing.
        other: Param,
    },
    /// The transfer-function output has an unknown extension.
    TransferFormat(PathBuf),
    /// `param` applies only to `only` output, not to `output`.
    OutputKind {
        /// The parameter given.
        param: Param,
        /// The outputs it applies to.
        only: &'static str,
        /// The output given.
        output: PathBuf,
    },
    /// `param` applies only to `only` input, not to `input` (the demo volume for `None`).
    InputKind {
        /// The parameter given.
        param: Param,
        /// The inputs it applies to.
        only: &'static str,
        /// The input given.
        input: Option<PathBuf>,
    },
    /// A spacing was given for a curvilinear grid (its points give the geometry).
    CurvilinearSpacing(PathBuf),
    /// A spacing was given for a closed surface (its grid has cubic voxels, set by the
    /// resolution or the voxel size).
    SurfaceSpacing(PathBuf),
    /// `param` and `other` set the same thing in two ways: one only may be given.
    Exclusive {
        /// The parameter given second.
        param: Param,
        /// The parameter given first.
        other: Param,
    },
    /// More worker threads than the machine takes.
    TooManyThreads {
        /// The threads asked for.
        threads: usize,
        /// The most accepted.
        max: usize,
        /// The machine's cores.
        cores: usize,
    },
    /// The output is refused (an unknown format), with the writer's message.
    Output(PipelineError),
}

impl Inapplicable {
    /// The message, each parameter named by `names`.
    pub fn render(&self, names: ParamNames) -> String {
        let n = |p: Param| names.of(p);
        match self {
            Inapplicable::OnlyWith { param, with } => {
                let with: Vec<&str> = with.iter().map(|&p| n(p)).collect();
                format!("{} applies only with {}", n(*param), with.join(" or "))
            }
            Inapplicable::NotWith { param, mode, why } => {
                format!("{} does not apply with {} ({why})", n(*param), n(*mode))
            }
            Inapplicable::InspectInput
            | Inapplicable::NeedsVolume(_)
            | Inapplicable::VolumeNeedsInterval => self.render_inspect(names),
            Inapplicable::NothingWith { param, other } => {
                format!("{} does nothing with {}", n(*param), n(*other))
            }
            Inapplicable::TransferFormat(path) => format!(
                "{} {}: unknown transfer-function format; use .json (ParaView preset) or .csv",
                n(Param::Transfer),
                path.display()
            ),
            Inapplicable::OutputKind {
                param,
                only,
                output,
            } => {
                format!(
                    "{} applies only to {only}, not {}",
                    n(*param),
                    output.display()
                )
            }
            Inapplicable::InputKind { param, only, input } => {
                let name = input_name(input.as_deref());
                format!("{} applies only to {only}, not {name}", n(*param))
            }
            Inapplicable::CurvilinearSpacing(input) => format!(
                "{} does not apply to a curvilinear grid ({}: its points give the geometry)",
                n(Param::Spacing),
                input.display()
            ),
            Inapplicable::SurfaceSpacing(input) => format!(
                "{} does not apply to a closed surface ({}: its grid has cubic voxels; use {} or \
                 {})",
                n(Param::Spacing),
                input.display(),
                n(Param::Resolution),
                n(Param::VoxelSize)
            ),
            Inapplicable::Exclusive { param, other } => {
                format!(
                    "{} and {} exclude each other: give one",
                    n(*other),
                    n(*param)
                )
            }
            Inapplicable::TooManyThreads {
                threads,
                max,
                cores,
            } => format!(
                "{} {threads}: too many worker threads: at most {max} on this machine ({cores} \
                 cores)",
                n(Param::Threads)
            ),
            Inapplicable::Output(e) => e.to_string(),
        }
    }

    /// [`Inapplicable::render`] of the refusals about `--inspect` and its volume.
    fn render_inspect(&self, names: ParamNames) -> String {
        let n = |p: Param| names.of(p);
        match self {
            Inapplicable::InspectInput => format!(
                "{} takes the meshes, not an {} volume: give the volume with {}",
                n(Param::Inspect),
                n(Param::Input),
                n(Param::Volume)
            ),
            Inapplicable::NeedsVolume(p) => format!(
                "{} applies with {} only together with {}",
                n(*p),
                n(Param::Inspect),
                n(Param::Volume)
            ),
            Inapplicable::VolumeNeedsInterval => format!(
                "{} needs the interval: {} A and/or {} B",
                n(Param::Volume),
                n(Param::Alpha),
                n(Param::Beta)
            ),
            // the other refusals are rendered by `render`
            _ => String::new(),
        }
    }
}

impl fmt::Display for Inapplicable {
    /// The message with the neutral names.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.render(ParamNames::NEUTRAL))
    }
}

impl std::error::Error for Inapplicable {}

/// The input as named in these messages.
fn input_name(input: Option<&Path>) -> String {
    input.map_or("the demo volume".to_string(), |p| p.display().to_string())
}

/// Parameters that only the critical points use (the JSON output also applies with an
/// inspection).
const CRITICAL_ONLY: [Param; 9] = [
    Param::Spectrum,
    Param::Transfer,
    Param::TransferDesign,
    Param::TransferWidth,
    Param::Persistence,
    Param::MinPersistence,
    Param::MinValue,
    Param::MaxValue,
    Param::Kind,
];

/// Parameters that only meshing uses.
const MESH_ONLY: [Param; 19] = [
    Param::MaxEdge,
    Param::Grading,
    Param::Alpha,
    Param::Beta,
    Param::Levels,
    Param::RegionNames,
    Param::Method,
    Param::Report,
    Param::MshVersion,
    Param::VtuEncoding,
    Param::Field,
    Param::Function,
    Param::Caps,
    Param::Ascii,
    Param::NoAnalysis,
    Param::CriticalTol,
    Param::NoCriticalCheck,
    Param::Resolution,
    Param::VoxelSize,
];

/// Parameters of the quality pass, which apply only with it.
const QUALITY_ONLY: [Param; 5] = [
    Param::MinAngle,
    Param::MaxAngle,
    Param::QualityTime,
    Param::BoundaryCollapseRatio,
    Param::SplitSag,
];

/// Parameters that apply to an inspection.
const INSPECT_OPTIONS: [Param; 9] = [
    Param::Inspect,
    Param::Volume,
    Param::Alpha,
    Param::Beta,
    Param::Spacing,
    Param::Json,
    Param::Threads,
    Param::Quiet,
    Param::MemoryLimit,
];

/// Checks that every parameter given applies to the mode, the output and the input, that
/// the output's format is known and that the thread count is within the machine's limit.
///
/// # Errors
/// The first parameter that does nothing (or the output, or the thread count).
pub fn check_applies(g: &Given) -> Result<(), Inapplicable> {
    if let Some((threads, max, cores)) = g.threads.and_then(too_many_threads) {
        return Err(Inapplicable::TooManyThreads {
            threads,
            max,
            cores,
        });
    }
    let only_with = |param, with| Err(Inapplicable::OnlyWith { param, with });
    match g.mode {
        Mode::Inspect => return check_inspect(g),
        _ if g.has(Param::Volume) => return only_with(Param::Volume, &[Param::Inspect]),
        Mode::Mesh if g.has(Param::Json) => {
            return only_with(Param::Json, &[Param::Critical, Param::Inspect])
        }
        Mode::Critical => {
            if let Some(param) = g.first(&MESH_ONLY) {
                return Err(Inapplicable::NotWith {
                    param,
                    mode: Param::Critical,
                    why: "it lists the critical points and meshes nothing",
                });
            }
            if g.input.is_some_and(is_surface) {
                return Err(Inapplicable::InputKind {
                    param: Param::Critical,
                    only: "a volume input",
                    input: g.input.map(Path::to_path_buf),
                });
            }
            return check_transfer(g.transfer);
        }
        Mode::Mesh => {}
    }
    if let Some(param) = g.first(&CRITICAL_ONLY) {
        return only_with(param, &[Param::Critical]);
    }
    if let (false, Some(param)) = (g.has(Param::Quality), g.first(&QUALITY_ONLY)) {
        return only_with(param, &[Param::Quality]);
    }
    if let (false, true) = (g.has(Param::MaxEdge), g.has(Param::Grading)) {
        return only_with(Param::Grading, &[Param::MaxEdge]);
    }
    check_output(g, g.output.unwrap_or(Path::new(DEMO_OUTPUT)))?;
    check_input(g)?;
    check_levels(g)?;
    if g.has(Param::NoCriticalCheck) && g.has(Param::CriticalTol) {
        return Err(Inapplicable::NothingWith {
            param: Param::CriticalTol,
            other: Param::NoCriticalCheck,
        });
    }
    Ok(())
}

/// Several levels: not with a bound of one interval, nor (yet) with a closed-surface input;
/// region names only with them.
fn check_levels(g: &Given) -> Result<(), Inapplicable> {
    if !g.has(Param::Levels) {
        return match g.has(Param::RegionNames) {
            true => Err(Inapplicable::OnlyWith {
                param: Param::RegionNames,
                with: &[Param::Levels],
            }),
            false => Ok(()),
        };
    }
    if let Some(param) = g.first(&[Param::Alpha, Param::Beta]) {
        return Err(Inapplicable::Exclusive {
            param,
            other: Param::Levels,
        });
    }
    match g.input.filter(|p| is_surface(p)) {
        Some(input) => Err(Inapplicable::InputKind {
            param: Param::Levels,
            only: "a volume input",
            input: Some(input.to_path_buf()),
        }),
        None => Ok(()),
    }
}

/// With an inspection: only its parameters, the interval and the spacing only with a
/// reference volume, and with one an interval.
fn check_inspect(g: &Given) -> Result<(), Inapplicable> {
    if g.input.is_some() {
        return Err(Inapplicable::InspectInput);
    }
    let other = Param::ALL
        .into_iter()
        .find(|p| g.has(*p) && !INSPECT_OPTIONS.contains(p));
    if let Some(param) = other {
        return Err(Inapplicable::NotWith {
            param,
            mode: Param::Inspect,
            why: "it inspects meshes and meshes nothing",
        });
    }
    if !g.has(Param::Volume) {
        if let Some(p) = g.first(&[Param::Alpha, Param::Beta, Param::Spacing]) {
            return Err(Inapplicable::NeedsVolume(p));
        }
    } else if !g.has(Param::Alpha) && !g.has(Param::Beta) {
        return Err(Inapplicable::VolumeNeedsInterval);
    }
    Ok(())
}

/// The format of the transfer-function output is known from its extension (a directory is
/// left to the run's check that the outputs can be written, which names it as one).
fn check_transfer(transfer: Option<&Path>) -> Result<(), Inapplicable> {
    match transfer {
        Some(path) if TransferFormat::from_path(path).is_none() && !path.is_dir() => {
            Err(Inapplicable::TransferFormat(path.to_path_buf()))
        }
        _ => Ok(()),
    }
}

/// The output's format is known and the parameters of other formats are not given.
fn check_output(g: &Given, output: &Path) -> Result<(), Inapplicable> {
    let surface = SurfaceFormat::from_path(output);
    let mesh = match surface {
        Some(_) => None,
        None => Some(
            MeshFormat::from_path(output)
                .map_err(|e| Inapplicable::Output(PipelineError::from(e)))?,
        ),
    };
    let refuse = |param, only| {
        Err(Inapplicable::OutputKind {
            param,
            only,
            output: output.to_path_buf(),
        })
    };
    if g.has(Param::MshVersion) && mesh != Some(MeshFormat::Msh) {
        return refuse(Param::MshVersion, ".msh output");
    }
    if g.has(Param::VtuEncoding) && mesh != Some(MeshFormat::Vtu) {
        return refuse(Param::VtuEncoding, ".vtu output");
    }
    if g.has(Param::MaxEdge) && surface.is_some() {
        return refuse(Param::MaxEdge, "volume mesh output (.msh, .inp, .vtu)");
    }
    if g.has(Param::Caps) && surface.is_none() {
        return refuse(Param::Caps, "isosurface output (.obj, .ply, .stl)");
    }
    if g.has(Param::Ascii) && !matches!(surface, Some(SurfaceFormat::Ply | SurfaceFormat::Stl)) {
        return refuse(Param::Ascii, ".ply and .stl output (.obj is always text)");
    }
    Ok(())
}

/// The parameters of curvilinear inputs are given with one, the spacing without one; those
/// of closed surfaces with one, and not both.
fn check_input(g: &Given) -> Result<(), Inapplicable> {
    let curvilinear = g.input.is_some_and(is_curvilinear);
    let plot3d = g.input.is_some_and(is_plot3d);
    let refuse = |param, only| {
        Err(Inapplicable::InputKind {
            param,
            only,
            input: g.input.map(Path::to_path_buf),
        })
    };
    if g.has(Param::MaxEdge) && curvilinear {
        return refuse(Param::MaxEdge, "a volume on a regular grid");
    }
    if g.has(Param::Field) && !curvilinear {
        return refuse(Param::Field, "a curvilinear grid input (.vts, .xyz)");
    }
    if g.has(Param::Function) && !plot3d {
        return refuse(Param::Function, "a Plot3D grid input (.xyz)");
    }
    check_surface_input(g)?;
    match g.input {
        Some(input) if g.has(Param::Spacing) && curvilinear => {
            Err(Inapplicable::CurvilinearSpacing(input.to_path_buf()))
        }
        _ => Ok(()),
    }
}

/// The resolution or the voxel size (not both) with a closed surface, no spacing.
fn check_surface_input(g: &Given) -> Result<(), Inapplicable> {
    let Some(input) = g.input.filter(|p| is_surface(p)) else {
        return match g.first(&[Param::Resolution, Param::VoxelSize]) {
            Some(param) => Err(Inapplicable::InputKind {
                param,
                only: "a closed-surface input (.obj, .ply, .stl)",
                input: g.input.map(Path::to_path_buf),
            }),
            None => Ok(()),
        };
    };
    if g.has(Param::Spacing) {
        return Err(Inapplicable::SurfaceSpacing(input.to_path_buf()));
    }
    if g.has(Param::Resolution) && g.has(Param::VoxelSize) {
        return Err(Inapplicable::Exclusive {
            param: Param::VoxelSize,
            other: Param::Resolution,
        });
    }
    Ok(())
}
