//! `chopperscape train`: the recipe's PPO learned in Rust (`chopperscape-learn`), into the run folder Python's
//! `python -m chopperscape.learn.train` writes: `recipe.json`, `progress.csv` (the same columns), the policy as
//! `model.onnx` (the format of `python -m chopperscape.learn.export`, which `demo`, `record`, `evaluate` and the
//! page play) and `resume.json` (what `--resume` goes on from) in place of `model.pt` and `resume.pt`.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result};
use chopperscape_learn::export::{ExportInfo, python_json, to_onnx};
use chopperscape_learn::phases::{Laps, NoLaps, PHASES, Phase};
use chopperscape_learn::progress::{COLUMNS, Row, header};
use chopperscape_learn::recipe::PRESETS;
use chopperscape_learn::{Learner, Recipe, State};
use clap::Args;

use crate::output::write_atomic;
use crate::{interrupt, note, say, usage_bail};

/// The files of a run in its folder.
pub const RUN_FILES: [&str; 4] = ["model.onnx", "progress.csv", "recipe.json", "resume.json"];
/// Updates between checkpoints (`model.onnx` and `resume.json`), as Python's.
pub const CHECKPOINT_EVERY: u64 = 50;
/// Updates between progress lines on standard error.
pub const REPORT_EVERY: u64 = 10;

/// Train a policy with PPO in Rust (the recipe of python -m chopperscape.learn.train).
///
/// Writes OUT/recipe.json, OUT/progress.csv (one row per update, the columns of Python's trainer),
/// OUT/model.onnx (play it with `demo --policy OUT/model.onnx`) and OUT/resume.json (for --resume), saved every
/// 50 updates, at the end and on Ctrl-C (the first Ctrl-C stops after the current update, once saved; a second
/// stops at once). Prints {"model": ..., "progress": ...} when done. Presets: fast (features at frame skip 4, 3 M
/// decisions, about two CPU minutes in torch) and features (the 15 M step recipe).
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  chopperscape train --preset fast --seed 0 --out runs/fast-0\n  \
chopperscape train --preset fast --out runs/fast-0 --resume\n  chopperscape demo --policy runs/fast-0/model.onnx")]
pub struct TrainArgs {
    /// The recipe preset
    #[arg(long, default_value = "fast", value_parser = clap::builder::PossibleValuesParser::new(PRESETS))]
    pub preset: String,
    /// Training seed: env i is reset with seed + i, and the network is initialised from it
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// The run folder
    #[arg(long)]
    pub out: PathBuf,
    /// Step budget in decisions (the preset's otherwise); the learning rate anneals over it
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1_000_000_000_000))]
    pub steps: Option<u64>,
    /// Stop after this many minutes of wall time (the schedule still follows the step budget)
    #[arg(long, value_parser = positive_minutes)]
    pub minutes: Option<f64>,
    /// Continue the run in --out from its resume.json
    #[arg(long, conflicts_with = "force")]
    pub resume: bool,
    /// Replace a run already in --out (it is first moved whole into OUT/replaced-N)
    #[arg(long)]
    pub force: bool,
    /// Envs stepped together (the preset's otherwise)
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub num_envs: Option<u32>,
    /// Steps of each env per update (the preset's otherwise)
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65_536))]
    pub num_steps: Option<u32>,
    /// Threads of the network's matrix products (candle's, through RAYON_NUM_THREADS)
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=256))]
    pub threads: u16,
    /// Threads that step the envs
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=256))]
    pub env_threads: u16,
    /// Time the update's phases (Python's: env, obs_norm, forward, ...) and print where the time went: a table
    /// on standard error and a "phases" object (seconds per phase) in the closing JSON line
    #[arg(long)]
    pub phases: bool,
}

/// The wall time of each [`Phase`], summed over a run, from the learner's laps.
struct Stopwatch {
    last: Instant,
    seconds: [f64; PHASES.len()],
}

impl Stopwatch {
    fn new() -> Stopwatch {
        Stopwatch { last: Instant::now(), seconds: [0.0; PHASES.len()] }
    }

    /// The table: each phase's seconds, microseconds a decision and share of the timed time.
    fn table(&self, decisions: u64) -> String {
        let total: f64 = self.seconds.iter().sum();
        let mut text = format!("{:<16}{:>10}{:>14}{:>8}\n", "phase", "seconds", "µs/decision", "share");
        for (name, s) in PHASES.iter().zip(self.seconds) {
            let per = s * 1e6 / decisions.max(1) as f64;
            text += &format!("{name:<16}{s:>10.2}{per:>14.2}{:>7.1}%\n", 100.0 * s / total.max(1e-12));
        }
        let per = total * 1e6 / decisions.max(1) as f64;
        text + &format!("{:<16}{total:>10.2}{per:>14.2}{:>7.1}%", "total", 100.0)
    }
}

impl Laps for Stopwatch {
    fn lap(&mut self, phase: Phase) {
        let now = Instant::now();
        self.seconds[phase as usize] += (now - self.last).as_secs_f64();
        self.last = now;
    }
}

fn positive_minutes(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(m) if m.is_finite() && m > 0.0 => Ok(m),
        _ => Err(format!("{s:?} is not a positive number of minutes")),
    }
}

/// Sets the matrix products' threads; called before any other thread exists.
pub fn set_threads(args: &TrainArgs) {
    // SAFETY: called from `main` before the signal thread or any other thread is started, so nothing reads the
    // environment concurrently.
    unsafe { std::env::set_var("RAYON_NUM_THREADS", args.threads.to_string()) };
}

/// The first free `OUT/replaced-N`.
fn next_aside(out: &Path) -> PathBuf {
    (1..).map(|n| out.join(format!("replaced-{n}"))).find(|p| std::fs::symlink_metadata(p).is_err()).unwrap_or_default()
}

/// Makes `out` ready for a new run (usage errors before anything is written), moving an old run aside with
/// `force`; returns where it went.
fn start_folder(out: &Path, force: bool) -> Result<Option<PathBuf>> {
    if std::fs::symlink_metadata(out).is_ok() && !out.is_dir() {
        usage_bail!("--out {}: it is not a folder", out.display());
    }
    let old: Vec<&str> = RUN_FILES.iter().copied().filter(|f| std::fs::symlink_metadata(out.join(f)).is_ok()).collect();
    if !old.is_empty() && !force {
        usage_bail!(
            "--out {} holds a run ({}): pass --force to replace it (it is kept in OUT/replaced-N), or --resume",
            out.display(),
            old.join(", ")
        );
    }
    std::fs::create_dir_all(out).with_context(|| format!("--out {}: cannot make the folder", out.display()))?;
    if old.is_empty() {
        return Ok(None);
    }
    let aside = next_aside(out);
    std::fs::create_dir(&aside).with_context(|| format!("cannot make {}", aside.display()))?;
    for f in old {
        std::fs::rename(out.join(f), aside.join(f))
            .with_context(|| format!("cannot move {f} into {}", aside.display()))?;
    }
    Ok(Some(aside))
}

/// The progress CSV of a resumed run: its rows up to `env_steps` kept (later rows are written again), opened for
/// appending.
fn resume_csv(path: &Path, env_steps: u64) -> Result<File> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut lines = text.lines();
    // A CSV written before the last column group was added (no `recon_loss`) resumes with those columns blank.
    let older = COLUMNS[..COLUMNS.len() - 1].join(",");
    let width = match lines.next() {
        Some(h) if h == header() => COLUMNS.len(),
        Some(h) if h == older => COLUMNS.len() - 1,
        _ => usage_bail!("{}: not a progress CSV this trainer wrote (its header differs)", path.display()),
    };
    let pad = ",".repeat(COLUMNS.len() - width);
    let mut kept = header() + "\n";
    for line in lines {
        let steps = line.split(',').next().and_then(|s| s.parse::<u64>().ok());
        if line.split(',').count() == width && steps.is_some_and(|s| s <= env_steps) {
            kept += line;
            kept += &pad;
            kept += "\n";
        }
    }
    write_atomic(path, kept.as_bytes(), true)?;
    OpenOptions::new().append(true).open(path).with_context(|| format!("cannot open {}", path.display()))
}

/// Runs the command.
///
/// # Errors
/// A usage error (a run in --out without --force, --resume without resume.json), or a failure while training or
/// writing; the model saved last is kept.
pub fn run(args: TrainArgs) -> Result<ExitCode> {
    keep_memory();
    let out = args.out.clone();
    let (mut learner, mut csv, wall_before) = if args.resume {
        let path = out.join("resume.json");
        let text = match std::fs::read_to_string(&path) {
            Ok(t) => t,
            Err(_) => {
                usage_bail!("--resume {}: no resume.json there (a run saves one every 50 updates)", out.display())
            }
        };
        let mut state: State = match serde_json::from_str(&text) {
            Ok(s) => s,
            Err(e) => usage_bail!("{}: not a resume state of this trainer ({e})", path.display()),
        };
        if let Some(steps) = args.steps {
            state.recipe.total_steps = steps;
        }
        let wall = state.wall_s;
        let steps = state.env_steps;
        let learner = match Learner::from_state(state) {
            Ok(l) => l,
            Err(e) => usage_bail!("--resume {}: {e}", out.display()),
        };
        (learner, resume_csv(&out.join("progress.csv"), steps)?, wall)
    } else {
        let mut recipe = Recipe::preset(&args.preset).expect("clap allows only the presets");
        recipe.seed = args.seed;
        recipe.torch_threads = usize::from(args.threads);
        recipe.env_threads = usize::from(args.env_threads);
        if let Some(steps) = args.steps {
            recipe.total_steps = steps;
        }
        recipe.num_envs = args.num_envs.map_or(recipe.num_envs, |n| n as usize);
        recipe.num_steps = args.num_steps.map_or(recipe.num_steps, |n| n as usize);
        if let Err(e) = recipe.check() {
            usage_bail!("{e}");
        }
        let aside = start_folder(&out, args.force)?;
        if let Some(aside) = aside {
            note!("note: --force: the run that was in {} is kept in {}", out.display(), aside.display());
        }
        let learner = Learner::new(recipe.clone())?;
        let json = serde_json::to_string_pretty(&recipe)? + "\n";
        write_atomic(&out.join("recipe.json"), json.as_bytes(), true)?;
        let mut csv = File::create(out.join("progress.csv")).context("cannot write progress.csv")?;
        writeln!(csv, "{}", header()).context("cannot write progress.csv")?;
        (learner, csv, 0.0)
    };
    interrupt::defer();
    let start = Instant::now();
    let cpu_start = cpu_seconds();
    let steps_start = learner.env_steps();
    let wall = |start: &Instant| wall_before + start.elapsed().as_secs_f64();
    let model = out.join("model.onnx");
    let total = learner.recipe().total_steps;
    let mut stopped = None;
    let mut watch = Stopwatch::new();
    while !learner.finished() {
        if let Some(signal) = interrupt::pending() {
            stopped = Some(signal);
            break;
        }
        if args.minutes.is_some_and(|m| start.elapsed().as_secs_f64() >= m * 60.0) {
            break;
        }
        let laps: &mut dyn Laps = if args.phases { &mut watch } else { &mut NoLaps };
        laps.lap(Phase::Logging); // what came since the last update: the checks above, the previous row's writing
        let mut row = match learner.update_laps(0.0, laps) {
            Ok(row) => row,
            Err(e) => {
                anyhow::bail!("training stopped: {e}; the model saved last is kept in {}", model.display())
            }
        };
        row.wall_s = wall(&start);
        writeln!(csv, "{}", row.csv_line()).context("cannot write progress.csv; the model saved last is kept")?;
        if learner.updates() % REPORT_EVERY == 0 {
            report(&row, total, learner.env_steps() - steps_start, start.elapsed().as_secs_f64());
        }
        if learner.updates() % CHECKPOINT_EVERY == 0 {
            save(&learner, &out, wall(&start))?;
        }
    }
    save(&learner, &out, wall(&start))?;
    watch.lap(Phase::Logging);
    let secs = start.elapsed().as_secs_f64();
    let decisions = learner.env_steps() - steps_start;
    note!(
        "{} decisions in {secs:.1} s wall, {:.1} s CPU ({:.0} decisions/s)",
        learner.env_steps(),
        cpu_seconds() - cpu_start,
        decisions as f64 / secs.max(1e-9)
    );
    if let Some(signal) = stopped {
        note!("stopped: the model reached so far ({} decisions) is saved in {}", learner.env_steps(), model.display());
        return Ok(ExitCode::from(u8::try_from(128 + signal).unwrap_or(1)));
    }
    let mut line = serde_json::json!({"model": model, "progress": out.join("progress.csv")});
    if args.phases {
        note!("{}", watch.table(decisions));
        let seconds: serde_json::Map<_, _> =
            PHASES.iter().zip(watch.seconds).map(|(k, v)| ((*k).to_string(), serde_json::json!(v))).collect();
        line["phases"] = serde_json::Value::Object(seconds);
        line["decisions"] = serde_json::json!(decisions);
    }
    say!("{line}")?;
    Ok(ExitCode::SUCCESS)
}

fn report(row: &Row, total: u64, decisions: u64, secs: f64) {
    let ret = row.returns.map_or_else(|| "-".to_string(), |(m, _, _)| format!("{m:.0}"));
    note!(
        "{:>9}/{total} decisions  return {ret:>6}  entropy {:.3}  {:.0} decisions/s",
        row.env_steps,
        row.entropy,
        decisions as f64 / secs.max(1e-9)
    );
}

/// Writes `model.onnx` and `resume.json`, each whole or not at all.
fn save(learner: &Learner, out: &Path, wall_s: f64) -> Result<()> {
    let recipe = learner.recipe();
    let info = ExportInfo {
        env_options: python_json(&recipe.env_options),
        train_seeds: vec![(recipe.seed, recipe.num_envs as u64)],
    };
    let onnx = to_onnx(learner.agent(), learner.obs_norm(), &info)?;
    write_atomic(&out.join("model.onnx"), &onnx, true)?;
    let mut state = learner.state()?;
    state.wall_s = wall_s;
    write_atomic(&out.join("resume.json"), serde_json::to_string(&state)?.as_bytes(), true)
}

/// Keeps freed memory in the process: every minibatch allocates and frees tensors of up to 2 MiB, which glibc by
/// default maps and unmaps each time (a third of the run's time went to the system, page faults, before this).
fn keep_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: mallopt only sets allocator parameters; called before the learner allocates.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
        libc::mallopt(libc::M_TOP_PAD, 64 << 20);
    }
}

/// CPU seconds of this process so far (user + system), where the system says.
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage writes the struct it is given.
    unsafe {
        let mut usage: libc::rusage = std::mem::zeroed();
        if libc::getrusage(libc::RUSAGE_SELF, &mut usage) != 0 {
            return f64::NAN;
        }
        let t = |v: libc::timeval| v.tv_sec as f64 + v.tv_usec as f64 * 1e-6;
        t(usage.ru_utime) + t(usage.ru_stime)
    }
}
