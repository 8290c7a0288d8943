//! `solver-demo`: solve `-div(k grad u) = s` on a mesh written by `tptd-mesh`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{anyhow, bail, Context, Result};
use clap::Parser;
use solver_demo::pcg::{PcgOptions, Preconditioner};
use solver_demo::run::{solve, Options};
use tptd::io::{check_clashes, RunFile};

/// Solve the steady heat / Poisson equation -div(k grad u) = s with P1 finite elements on a
/// tetrahedral mesh (.msh 4.1/2.2 or .inp) and write u, grad u and the flux as .vtu.
#[derive(Parser, Debug)]
#[command(version)]
struct Cli {
    /// Input mesh (.msh or .inp, as written by tptd-mesh).
    mesh: PathBuf,
    /// Output .vtu (u at the nodes, grad_u and flux = -k grad u per tetrahedron).
    #[arg(short, long, value_name = "OUT.vtu", required_unless_present = "mms")]
    output: Option<PathBuf>,
    /// Conductivity: K everywhere, or REGION=K for one region; repeatable.
    #[arg(long = "k", value_name = "K|REGION=K", allow_hyphen_values = true)]
    k: Vec<String>,
    /// Constant source term s.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    source: f64,
    /// Dirichlet value on a node group, e.g. alpha=0; repeatable, later groups win on shared nodes.
    #[arg(long, value_name = "NAME=VALUE", allow_hyphen_values = true)]
    dirichlet: Vec<String>,
    /// Relative residual tolerance of the conjugate-gradient solver.
    #[arg(long, value_name = "T", default_value_t = 1e-10)]
    tol: f64,
    /// Iteration limit of the solver.
    #[arg(long, value_name = "N", default_value_t = 20_000)]
    max_iter: usize,
    /// Preconditioner.
    #[arg(long, value_enum, default_value_t = PrecondArg::Jacobi)]
    precond: PrecondArg,
    /// Assemble through sprs triplets (TriMat -> CSR) instead of row by row (for comparison).
    #[arg(long)]
    triplets: bool,
    /// Manufactured solution: solves -div(k grad u) = 4.75 k g, g = sin(2x) cos(y) exp(z/2)
    /// (one constant k), with u = g on the whole boundary, whose exact solution is u = g; prints
    /// the L2 and H1 errors relative to the norms of g (coordinates as in the mesh file: g
    /// oscillates with period about 3 units and grows as exp(z/2), so meshes many units wide
    /// need many elements).
    #[arg(long)]
    mms: bool,
    /// Worker threads (default: all cores).
    #[arg(short = 'j', long, value_name = "N")]
    threads: Option<usize>,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum PrecondArg {
    None,
    Jacobi,
}

/// Parses `NAME=VALUE`.
fn name_value(s: &str) -> Result<(String, f64)> {
    let (n, v) = s
        .split_once('=')
        .with_context(|| format!("expected NAME=VALUE, got {s:?}"))?;
    let v: f64 = v
        .trim()
        .parse()
        .with_context(|| format!("invalid number in {s:?}"))?;
    Ok((n.trim().to_string(), v))
}

fn options(cli: &Cli) -> Result<Options> {
    let mut opts = Options {
        source: cli.source,
        mms: cli.mms,
        triplets: cli.triplets,
        ..Options::default()
    };
    for k in &cli.k {
        if k.contains('=') {
            opts.k_regions.push(name_value(k)?);
        } else {
            opts.k = k.parse().with_context(|| format!("invalid --k {k:?}"))?;
        }
    }
    for d in &cli.dirichlet {
        opts.dirichlet.push(name_value(d)?);
    }
    if !(cli.tol > 0.0 && cli.tol < 1.0) {
        bail!("--tol must be in (0, 1), got {}", cli.tol);
    }
    let preconditioner = match cli.precond {
        PrecondArg::None => Preconditioner::None,
        PrecondArg::Jacobi => Preconditioner::Jacobi,
    };
    opts.pcg = PcgOptions {
        tol: cli.tol,
        max_iter: cli.max_iter,
        preconditioner,
    };
    Ok(opts)
}

/// Prints progress to stderr once the solve runs longer than 2 s, at most once a second.
fn progress_printer() -> impl FnMut(usize, f64) {
    let mut start = None;
    let mut last = 0.0;
    move |it, res| {
        let t = start
            .get_or_insert_with(Instant::now)
            .elapsed()
            .as_secs_f64();
        if t > 2.0 && t - last >= 1.0 {
            last = t;
            eprintln!("  iteration {it}: relative residual {res:.3e} ({t:.1} s)");
        }
    }
}

/// A usage error (exit status 2): an output that is not `.vtu` or that is the same file as
/// the input mesh.
#[derive(Debug, thiserror::Error)]
enum UsageError {
    /// The output extension is not `.vtu`.
    #[error("{}: the output is written as VTU; name it with a .vtu extension", .0.display())]
    NotVtu(PathBuf),
    /// The output is the input.
    #[error(transparent)]
    Clash(#[from] tptd::io::FileClash),
}

/// Checks the output before any work: not the input mesh (compared by
/// identity, not spelling), a `.vtu` name, in a directory that exists.
fn check_output(cli: &Cli, out: &Path) -> Result<()> {
    let input = [RunFile::new("the input mesh", &cli.mesh)];
    check_clashes(&input, &[RunFile::new("-o", out)]).map_err(UsageError::from)?;
    let vtu = out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vtu"));
    if !vtu {
        return Err(UsageError::NotVtu(out.to_path_buf()).into());
    }
    tptd::io::check_writable(out)?;
    Ok(())
}

fn run(cli: &Cli) -> Result<()> {
    if let Some(out) = &cli.output {
        check_output(cli, out)?;
    }
    let opts = options(cli)?;
    let t = Instant::now();
    let file = tptd::io::read_mesh(&cli.mesh)?;
    let t_read = t.elapsed().as_secs_f64();
    let sol = solve(&file, &opts, &mut progress_printer())
        .map_err(|e| anyhow!("{}: {e}", cli.mesh.display()))?;
    println!(
        "nodes: {}  tetrahedra: {}",
        file.mesh.points.len(),
        file.mesh.tets.len()
    );
    println!(
        "unknowns: {}  matrix non-zeros: {}",
        sol.unknowns, sol.nonzeros
    );
    println!(
        "iterations: {}  final relative residual: {:.3e}",
        sol.report.iterations, sol.report.residual
    );
    if let Some(e) = sol.mms {
        println!("mms problem: {}", solver_demo::mms::PROBLEM);
        println!(
            "mms relative errors: L2 {:.6e}  H1 {:.6e}  (|u - u_h|_L2 / |u|_L2 and \
             |grad(u - u_h)|_L2 / |grad u|_L2; |u|_L2 = {:.3e}, |grad u|_L2 = {:.3e})",
            e.relative_l2(),
            e.relative_h1(),
            e.exact_l2,
            e.exact_h1
        );
    }
    let mut times = vec![("read", t_read)];
    times.extend(sol.times.iter().copied());
    // An unconverged solution is not written (nor does it replace an existing file).
    if let Some(out) = cli.output.as_ref().filter(|_| sol.report.converged) {
        let t = Instant::now();
        solver_demo::output::write_solution(out, &file.mesh, &sol.u, &sol.k)?;
        times.push(("write", t.elapsed().as_secs_f64()));
    }
    let list: Vec<String> = times.iter().map(|(n, s)| format!("{n} {s:.3}")).collect();
    println!("times (s): {}", list.join("  "));
    if !sol.report.converged {
        bail!(
            "the solver did not reach --tol {} in {} iterations (residual {:.3e})",
            cli.tol,
            sol.report.iterations,
            sol.report.residual
        );
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(n) = cli.threads {
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
        {
            eprintln!("solver-demo: error: {e}");
            return ExitCode::FAILURE;
        }
    }
    match run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Every error here is one line that already says what and where.
            eprintln!("solver-demo: error: {e}");
            if e.is::<UsageError>() {
                ExitCode::from(2)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}
