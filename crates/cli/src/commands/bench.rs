//! `chopperscape bench`: steps per second of the env and the vector env, median of several timed runs.

use std::process::ExitCode;
use std::time::{Duration, Instant};

use anyhow::Result;
use chopperscape::policy::{Policy, RandomPolicy};
use chopperscape::{ChopperScape, Config, ObsBufMut, ObsType, World};
use chopperscape_vector::VectorEnv;
use clap::Args;
use serde::Serialize;

use crate::options::GameOptions;
use crate::progress;

/// Every scenario name, as `--scenario` accepts it.
pub const SCENARIOS: &[&str] =
    &["features", "rgb_600x800", "rgb_600x800_incremental", "gray_84x84", "vector_features", "vector_gray_84x84"];

/// Environments per batch in the vector scenarios: enough that two threads pay off, few enough that a batch of
/// 84 × 84 frames stays in cache.
pub const VECTOR_ENVS: usize = 256;

/// Measure steps per second (median of several runs).
///
/// Scenarios: `features`, `rgb_600x800`, `gray_84x84` (one env, one thread, the observation of that name, copied
/// out to a buffer every step), `rgb_600x800_incremental` (the same, drawn incrementally onto the buffer with
/// `step_into_incremental`) and `vector_features`, `vector_gray_84x84` (256 envs stepped together, on 1 thread and
/// on all threads). Actions
/// are a fixed pseudo-random sequence; episodes reset when they end. Build with --release for real numbers.
#[derive(Args, Debug)]
#[command(after_help = "Examples:\n  cargo run --release -p chopperscape-cli -- bench\n  \
chopperscape bench --json --seconds 1 --runs 7\n  chopperscape bench --scenario features")]
pub struct BenchArgs {
    /// Print {"scenarios": [{"name": ..., "threads": ..., "steps_per_sec": ...}, ...]}
    #[arg(long)]
    pub json: bool,
    /// Seconds of each timed run
    #[arg(long, default_value_t = 0.3, allow_negative_numbers = true, value_parser = measurable_seconds)]
    pub seconds: f64,
    /// Timed runs per scenario (the median is reported), at least 1
    #[arg(long, default_value_t = 5, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..))]
    pub runs: u32,
    /// Only these scenarios (repeatable) [default: all]
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(SCENARIOS))]
    pub scenario: Vec<String>,
    #[command(flatten)]
    pub options: GameOptions,
}

/// The shortest timed run, in seconds: shorter ones would time the clock, not the env.
pub const MIN_SECONDS: f64 = 0.01;
/// The longest timed run, in seconds.
pub const MAX_SECONDS: f64 = 600.0;

fn measurable_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if (MIN_SECONDS..=MAX_SECONDS).contains(&v) => Ok(v),
        Ok(v) if v > 0.0 && v < MIN_SECONDS => {
            Err(format!("{s} s is too short to measure; give a number of seconds in [{MIN_SECONDS}, {MAX_SECONDS}]"))
        }
        _ => Err(format!("{s} is not a number of seconds in [{MIN_SECONDS}, {MAX_SECONDS}]")),
    }
}

/// One measured scenario.
#[derive(Serialize, Debug)]
struct Measured {
    name: &'static str,
    threads: usize,
    steps_per_sec: f64,
}

/// A scenario ready to run: steps it a batch at a time and says how many env steps that was.
type Stepper = Box<dyn FnMut() -> u64>;

/// Runs `bench`.
pub fn run(args: BenchArgs) -> Result<ExitCode> {
    let base = args.options.apply(Config::default())?;
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut plan: Vec<(&'static str, usize)> = Vec::new();
    for &name in SCENARIOS {
        if !args.scenario.is_empty() && !args.scenario.iter().any(|s| s == name) {
            continue;
        }
        if name.starts_with("vector_") {
            plan.push((name, 1));
            if all > 1 {
                plan.push((name, all));
            }
        } else {
            plan.push((name, 1));
        }
    }
    let bar = progress::bar(plan.len() as u64, "bench", args.json);
    let mut measured = Vec::new();
    for (name, threads) in plan {
        bar.set_message(name);
        let mut stepper = scenario(name, threads, &base)?;
        let sps = median_rate(&mut stepper, Duration::from_secs_f64(args.seconds), args.runs);
        measured.push(Measured { name, threads, steps_per_sec: sps });
        bar.inc(1);
    }
    bar.finish_and_clear();
    if args.json {
        #[derive(Serialize)]
        struct Report<'a> {
            scenarios: &'a [Measured],
        }
        crate::say!("{}", serde_json::to_string(&Report { scenarios: &measured })?)?;
    } else {
        crate::say!("{:<24} {:>7} {:>16}", "scenario", "threads", "steps/s")?;
        for m in &measured {
            crate::say!("{:<24} {:>7} {:>16.0}", m.name, m.threads, m.steps_per_sec)?;
        }
        crate::say!("median of {} runs of {} s each{}", args.runs, args.seconds, build_note())?;
    }
    Ok(ExitCode::SUCCESS)
}

fn build_note() -> &'static str {
    if cfg!(debug_assertions) { " (debug build: use --release for real numbers)" } else { "" }
}

/// A fixed pseudo-random action sequence (the random policy's, seed 0).
fn actions(n: usize) -> Vec<i64> {
    let mut policy = RandomPolicy::new(0);
    let world = World::default();
    (0..n).map(|_| policy.act(&world) as i64).collect()
}

fn config_for(name: &str, base: &Config) -> Config {
    let mut c = base.clone();
    match name {
        "features" | "vector_features" => c.obs_type = ObsType::Features,
        "rgb_600x800" | "rgb_600x800_incremental" => {
            c.obs_type = ObsType::Rgb;
            c.obs_size = (600, 800);
        }
        _ => {
            c.obs_type = ObsType::Grayscale;
            c.obs_size = (84, 84);
        }
    }
    c
}

fn scenario(name: &'static str, threads: usize, base: &Config) -> Result<Stepper> {
    let config = config_for(name, base);
    let acts = actions(4096);
    if name.starts_with("vector_") {
        let mut venv = VectorEnv::new(config, VECTOR_ENVS, threads)?;
        venv.reset(Some(0))?;
        let mut k = 0;
        return Ok(Box::new(move || {
            let start = (k * VECTOR_ENVS) % (acts.len() - VECTOR_ENVS);
            venv.step(&acts[start..start + VECTOR_ENVS]).expect("actions are valid");
            k += 1;
            VECTOR_ENVS as u64
        }));
    }
    let mut env = ChopperScape::new(config)?;
    let pixels = env.config().obs_type.is_pixels();
    let (mut u8s, mut f32s) =
        if pixels { (vec![0u8; env.obs_len()], Vec::new()) } else { (Vec::new(), vec![0f32; env.obs_len()]) };
    let incremental = name.ends_with("_incremental");
    let mut seed = 0u64;
    let mut i = 0usize;
    env.reset_into(Some(seed), buf(pixels, &mut u8s, &mut f32s))?;
    Ok(Box::new(move || {
        const CHUNK: u64 = 256;
        for _ in 0..CHUNK {
            let (action, out) = (acts[i % acts.len()], buf(pixels, &mut u8s, &mut f32s));
            let t = if incremental { env.step_into_incremental(action, out) } else { env.step_into(action, out) }
                .expect("valid action");
            i += 1;
            if t.terminated || t.truncated {
                seed += 1;
                env.reset_into(Some(seed), buf(pixels, &mut u8s, &mut f32s)).expect("fitting buffer");
            }
        }
        CHUNK
    }))
}

fn buf<'a>(pixels: bool, u8s: &'a mut [u8], f32s: &'a mut [f32]) -> ObsBufMut<'a> {
    if pixels { ObsBufMut::U8(u8s) } else { ObsBufMut::F32(f32s) }
}

/// One warm-up run, then the median of `runs` timed runs of about `each`.
fn median_rate(stepper: &mut Stepper, each: Duration, runs: u32) -> f64 {
    let mut once = || {
        let start = Instant::now();
        let mut steps = 0u64;
        while start.elapsed() < each {
            steps += stepper();
        }
        steps as f64 / start.elapsed().as_secs_f64()
    };
    once();
    let mut rates: Vec<f64> = (0..runs).map(|_| once()).collect();
    rates.sort_by(f64::total_cmp);
    rates[rates.len() / 2]
}
