//! Steps a `features` env a fixed number of times (for profilers: `valgrind --tool=callgrind`, `perf`):
//! `cargo run --release -p chopperscape-core --example step_loop -- 1000000`.
use chopperscape::{ChopperScape, Config, ObsBufMut};

fn main() {
    let n: u64 = std::env::args().nth(1).and_then(|s| s.parse().ok()).unwrap_or(1_000_000);
    let mut env = ChopperScape::new(Config::features()).unwrap();
    let mut obs = vec![0f32; env.obs_len()];
    env.reset_into(Some(0), ObsBufMut::F32(&mut obs)).unwrap();
    let mut total = 0.0;
    for i in 0..n {
        let t = env.step_into((i % 5) as i64, ObsBufMut::F32(&mut obs)).unwrap();
        total += t.reward;
        if t.terminated || t.truncated {
            env.reset_into(None, ObsBufMut::F32(&mut obs)).unwrap();
        }
    }
    println!("{n} steps, total reward {total}, last obs[0] {}", obs[0]);
}
