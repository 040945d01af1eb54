//! Writes the native frame for a seed and a list of actions to stdout (600 × 800 × 3 RGB bytes): the
//! reference the browser test compares the page's frame with.
//!
//! `cargo run -p chopperscape-web --example frame -- --seed 5 --actions 0,0,3,3,4 [--option lives=3]... > frame.rgb`
//!
//! It drives the core directly (not the web wrapper), and stops early if the episode ends.

use std::io::Write;

use chopperscape::{ChopperScape, Config, Env};

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(2);
    }
}

fn run() -> Result<(), String> {
    let usage = "usage: frame --seed N --actions A,A,... [--option NAME=VALUE]...";
    let mut seed = None;
    let mut actions = Vec::new();
    let mut config = Config::default();
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        let value = args.next().ok_or_else(|| format!("{flag} needs a value; {usage}"))?;
        match flag.as_str() {
            "--seed" => seed = Some(value.parse::<u64>().map_err(|_| format!("--seed {value}: not an integer"))?),
            "--actions" => {
                actions = value
                    .split(',')
                    .filter(|s| !s.is_empty())
                    .map(|a| a.trim().parse::<i64>().map_err(|_| format!("--actions: `{a}` is not an action 0..=4")))
                    .collect::<Result<_, _>>()?
            }
            "--option" => {
                let (name, v) =
                    value.split_once('=').ok_or_else(|| format!("--option {value}: expected NAME=VALUE"))?;
                config.set(name, v).map_err(|e| e.to_string())?;
            }
            _ => return Err(format!("unknown argument {flag}; {usage}")),
        }
    }
    let seed = seed.ok_or_else(|| format!("--seed is required; {usage}"))?;
    let mut env = ChopperScape::new(config).map_err(|e| e.to_string())?;
    env.reset(Some(seed));
    for a in actions {
        if env.world().status.is_over() {
            break;
        }
        env.step(a).map_err(|e| e.to_string())?;
    }
    std::io::stdout().lock().write_all(&env.render()).map_err(|e| e.to_string())
}
