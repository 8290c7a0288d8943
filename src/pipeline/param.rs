//! The parameters of the requests as messages name them: [`Param`] is each one, and
//! [`ParamNames`] how a front end spells it (a command line `--alpha`, a binding `alpha`).
//! The library's messages put the name in through the request's [`ParamNames`], so that
//! each front end reads its own spelling; the default is the neutral name ([`Param::name`]).

use std::fmt;

/// Declares [`Param`] with one line per parameter: its variant and its neutral name.
macro_rules! params {
    ($($variant:ident => $name:literal,)*) => {
        /// A parameter of a meshing, critical-point or inspection request.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        #[allow(missing_docs)] // each variant is the parameter of its name
        pub enum Param {
            $($variant,)*
        }

        impl Param {
            /// Every parameter.
            pub const ALL: [Param; [$(Param::$variant,)*].len()] = [$(Param::$variant,)*];

            /// The neutral name: snake case, e.g. `alpha`, `quality_time`.
            pub fn name(self) -> &'static str {
                match self {
                    $(Param::$variant => $name,)*
                }
            }
        }
    };
}

params! {
    Input => "input",
    Output => "output",
    Alpha => "alpha",
    Beta => "beta",
    Levels => "levels",
    RegionNames => "region_names",
    Method => "method",
    Report => "report",
    Threads => "threads",
    MshVersion => "msh_version",
    VtuEncoding => "vtu_encoding",
    Spacing => "spacing",
    Resolution => "resolution",
    VoxelSize => "voxel_size",
    Field => "field",
    Function => "function",
    Caps => "caps",
    Ascii => "ascii",
    NoAnalysis => "no_analysis",
    Check => "check",
    Quality => "quality",
    MinAngle => "min_angle",
    MaxAngle => "max_angle",
    QualityTime => "quality_time",
    BoundaryCollapseRatio => "boundary_collapse_ratio",
    SplitSag => "split_sag",
    MaxEdge => "max_edge",
    Grading => "grading",
    Demo => "demo",
    MemoryLimit => "memory_limit",
    Quiet => "quiet",
    Critical => "critical",
    Json => "json",
    Inspect => "inspect",
    Volume => "volume",
    Spectrum => "spectrum",
    Transfer => "transfer",
    TransferDesign => "transfer_design",
    TransferWidth => "transfer_width",
    Persistence => "persistence",
    MinPersistence => "min_persistence",
    MinValue => "min_value",
    MaxValue => "max_value",
    Kind => "kind",
    CriticalTol => "critical_tol",
    NoCriticalCheck => "no_critical_check",
}

impl Param {
    /// The parameter of neutral name `name`.
    pub fn from_name(name: &str) -> Option<Param> {
        Param::ALL.into_iter().find(|p| p.name() == name)
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// How a front end spells the parameters in messages: a function of the parameter.
#[derive(Clone, Copy)]
pub struct ParamNames(pub fn(Param) -> &'static str);

impl ParamNames {
    /// The neutral names ([`Param::name`]).
    pub const NEUTRAL: ParamNames = ParamNames(Param::name);

    /// The name of `p`.
    pub fn of(self, p: Param) -> &'static str {
        (self.0)(p)
    }
}

impl Default for ParamNames {
    fn default() -> Self {
        ParamNames::NEUTRAL
    }
}

impl fmt::Debug for ParamNames {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("ParamNames")
    }
}

impl PartialEq for ParamNames {
    /// Names are equal when they name every parameter alike.
    fn eq(&self, other: &Self) -> bool {
        Param::ALL.iter().all(|&p| self.of(p) == other.of(p))
    }
}
