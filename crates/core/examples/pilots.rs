//! Plays episodes with a built-in pilot and prints steps, return and cause of each: `cargo run --release -p chopperscape-core --example pilots -- heuristic 20`.
use chopperscape::{Config, Game, Status, policy};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map(String::as_str).unwrap_or("heuristic");
    let n: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10);
    let mut total = 0;
    for seed in 0..n {
        let mut game = Game::new(Config::features()).unwrap();
        let mut p = policy::by_name(name, seed).unwrap();
        game.reset(Some(seed));
        while !game.world().status.is_over() {
            let a = p.act(game.world());
            game.step(a).unwrap();
        }
        let w = game.world();
        total += w.episode_return;
        let cause = match w.status {
            Status::Terminated(c) => c.as_str(),
            _ => "truncated",
        };
        println!("seed {seed}: steps {} return {} cause {cause}", w.steps, w.episode_return);
    }
    println!("mean return {}", total as f64 / n as f64);
}
