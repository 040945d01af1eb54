//! Plays episodes with a built-in policy and prints steps, return and cause of each, then the mean ± std return:
//! `cargo run --release -p chopperscape-core --example policies -- heuristic 20 [option=value …]`
//! (options as `Config::set` names them, e.g. `frame_skip=4 sticky_prob=0.25`; seeds 0, 1, …).
use chopperscape::{Config, Game, Status, policy};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map(String::as_str).unwrap_or("heuristic");
    let n: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10);
    let mut config = Config::features();
    for kv in args.iter().skip(3) {
        let (k, v) = kv.split_once('=').unwrap_or_else(|| panic!("options are name=value, got {kv}"));
        config.set(k, v).unwrap_or_else(|e| panic!("{e}"));
    }
    let mut returns = Vec::new();
    for seed in 0..n {
        let mut game = Game::new(config.clone()).unwrap();
        let mut p = policy::by_name(name, seed, &config).unwrap();
        game.reset(Some(seed));
        while !game.world().status.is_over() {
            let a = p.act(game.world());
            game.step(a).unwrap();
        }
        let w = game.world();
        returns.push(w.episode_return as f64);
        let cause = match w.status {
            Status::Terminated(c) => c.as_str(),
            _ => "truncated",
        };
        println!("seed {seed}: steps {} return {} cause {cause}", w.steps, w.episode_return);
    }
    let mean = returns.iter().sum::<f64>() / n as f64;
    let std = (returns.iter().map(|r| (r - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
    println!("mean return {mean:.1} ± {std:.1} over {n} episodes");
}
