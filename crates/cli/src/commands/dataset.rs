//! `chopperscape dataset`: episodes of a built-in policy (or replayed action logs) as a Minari dataset.
//!
//! Minari's on-disk format (HDF5 plus JSON metadata) is written by Minari's own Python classes, so this command
//! runs the Python package: `python -m chopperscape.integrations.datasets` with the same arguments. It needs the `chopperscape`
//! Python package and `minari[hdf5]` in the interpreter named by `CHOPPERSCAPE_PYTHON` (default `python3`), and
//! says so when they are missing.
//!
//! The child stops with this process: SIGINT, SIGTERM or SIGHUP is passed on to it and waited for (it removes its
//! unfinished dataset itself), and if this process is killed outright the child gets SIGTERM (Linux). Its exit
//! status is this command's. Defaults (`features` observations, the heuristic policy, one episode, seed 0) are
//! the Python module's own, so there is one of each.

use std::path::PathBuf;
use std::process::{Command, ExitCode, ExitStatus, Stdio};

use anyhow::{Context, Result};
use clap::Args;

use super::policy_name_parser;
use crate::interrupt::{self, Cleanup};
use crate::options::GameOptions;
use crate::usage_bail;

/// The environment variable naming the Python interpreter to run.
pub const PYTHON_VAR: &str = "CHOPPERSCAPE_PYTHON";

/// Write a Minari dataset of ChopperScape-v0 episodes (needs the chopperscape Python package and minari).
///
/// Episode i is played from seed S+i with the policy seeded S+i, exactly as `demo` plays it. The dataset goes
/// under MINARI_DATASETS_PATH (default ~/.minari/datasets), where `minari.load_dataset(NAME)` finds it; an
/// existing dataset is never overwritten. The work is done by `python -m chopperscape.integrations.datasets` in the
/// interpreter named by CHOPPERSCAPE_PYTHON (default python3), which needs `pip install chopperscape
/// "minari[hdf5]" pillow`.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  \
chopperscape dataset --policy heuristic --episodes 100 --obs-type features --out chopperscape/heuristic-v0\n  \
chopperscape dataset --from-logs run1.json run2.json --obs-type grayscale --obs-size 84x84 --out me/human-v0")]
pub struct DatasetArgs {
    /// The dataset id, `namespace/name-vN` (or `name-vN`)
    #[arg(long, value_name = "NAME")]
    pub out: String,
    /// The policy: random, heuristic, or a fixed action (right, left, down, up, noop) [default: heuristic]
    #[arg(long, value_parser = policy_name_parser(), conflicts_with = "from_logs")]
    pub policy: Option<String>,
    /// Number of episodes, at least 1 [default: 1]
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..), conflicts_with = "from_logs")]
    pub episodes: Option<u32>,
    /// Seed of the first episode [default: 0]
    #[arg(long, value_parser = super::seed_parser, conflicts_with = "from_logs")]
    pub seed: Option<u64>,
    /// Observation: rgb, rgb_float, grayscale or features [default: features]
    #[arg(long, value_parser = ["rgb", "rgb_float", "grayscale", "features"])]
    pub obs_type: Option<String>,
    /// Pixel observation size HxW, e.g. 84x84 [default: 600x800]
    #[arg(long, value_name = "HxW")]
    pub obs_size: Option<String>,
    /// Stack the last K observations
    #[arg(long, value_name = "K")]
    pub frame_stack: Option<u32>,
    /// Leave the HUD out of pixel observations
    #[arg(long)]
    pub no_hud: bool,
    /// Replay these action logs (`play --save-actions`) instead of a policy; the rules come from the logs
    #[arg(long, value_name = "LOG", num_args = 1..)]
    pub from_logs: Vec<PathBuf>,
    #[command(flatten)]
    pub options: GameOptions,
}

/// Runs `dataset`.
pub fn run(args: DatasetArgs) -> Result<ExitCode> {
    let python = std::env::var(PYTHON_VAR).unwrap_or_else(|_| "python3".to_string());
    if !args.from_logs.is_empty() && !args.options.given().is_empty() {
        usage_bail!("--from-logs replays the logs under their own rules: game options cannot be given with it");
    }
    args.options.apply(chopperscape::Config::default())?; // a flag that contradicts --mode is refused here
    check_python(&python)?;
    let mut cmd = Command::new(&python);
    cmd.args(["-m", "chopperscape.integrations.datasets", "--out", &args.out]);
    let mut option = |name: &str, value: &str| {
        cmd.args(["--option", &format!("{name}={value}")]);
    };
    if let Some(obs_type) = &args.obs_type {
        option("obs_type", obs_type);
    }
    if let Some(size) = &args.obs_size {
        option("obs_size", size);
    }
    if let Some(k) = args.frame_stack {
        option("frame_stack", &k.to_string());
    }
    if args.no_hud {
        option("hud", "false");
    }
    if let Some(style) = args.options.get("hud_style") {
        option("hud_style", style);
    }
    for (name, value) in args.options.given() {
        option(name, value);
    }
    if let Some(policy) = &args.policy {
        cmd.args(["--policy", policy]);
    }
    if let Some(episodes) = args.episodes {
        cmd.args(["--episodes", &episodes.to_string()]);
    }
    if let Some(seed) = args.seed {
        cmd.args(["--seed", &seed.to_string()]);
    }
    if !args.from_logs.is_empty() {
        cmd.arg("--from-logs").args(&args.from_logs);
    }
    interrupt::die_with_parent(&mut cmd);
    let mut child = cmd.spawn().with_context(|| format!("cannot run {python}"))?;
    let registered = interrupt::register(Cleanup::Stop(child.id()));
    let status = child.wait().with_context(|| format!("cannot wait for {python}"))?;
    if interrupt::is_stopping() {
        // The signal handler stopped the child and exits with the signal's status.
        loop {
            std::thread::park();
        }
    }
    drop(registered);
    Ok(ExitCode::from(exit_status(status)))
}

/// The child's exit status as this command's: its code, or 128 + the signal that ended it.
fn exit_status(status: ExitStatus) -> u8 {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            return u8::try_from(128 + signal).unwrap_or(1);
        }
    }
    status.code().and_then(|c| u8::try_from(c).ok()).unwrap_or(1)
}

/// Fails with what to install when `python` cannot import the package and Minari.
fn check_python(python: &str) -> Result<()> {
    let probe = Command::new(python)
        .args(["-c", "from chopperscape.integrations.datasets.place import minari_modules; minari_modules()"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output();
    let hint = format!(
        "`chopperscape dataset` writes Minari datasets through the chopperscape Python package: install it with \
         `pip install chopperscape \"minari[hdf5]\" pillow` (or `pip install ./python` from the repository), or \
         name the interpreter that has them with {PYTHON_VAR}=/path/to/python"
    );
    match probe {
        Err(e) => anyhow::bail!("cannot run the Python interpreter `{python}` ({e}): {hint}"),
        Ok(out) if !out.status.success() => {
            let err = String::from_utf8_lossy(&out.stderr);
            let last = err.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("").trim();
            anyhow::bail!("`{python}` cannot import chopperscape.integrations.datasets ({last}): {hint}")
        }
        Ok(_) => Ok(()),
    }
}
