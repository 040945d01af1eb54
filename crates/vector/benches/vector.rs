//! Steps per second of a batch: `features` and `grayscale` 84 × 84, at 1 and 2 threads.
//! Run with `cargo bench -p chopperscape-vector`. Each iteration is one batch of `N` steps; divan's
//! throughput counter reports environment steps per second.

use chopperscape::{Config, ObsType};
use chopperscape_vector::VectorEnv;
use divan::counter::ItemsCount;
use divan::{Bencher, black_box};

fn main() {
    divan::main();
}

/// Environments per batch.
const N: usize = 256;

fn bench_batch(bencher: Bencher, config: Config, threads: usize) {
    let mut venv = VectorEnv::new(config, N, threads).unwrap();
    // The same buffers every batch, read and not written between batches: pixels are drawn incrementally.
    venv.set_persistent_observations(true);
    let mut out = venv.new_buffers();
    venv.reset_into(Some(0), out.as_mut()).unwrap();
    // A fixed cycle of every action, different per environment, so choppers spread over the screen.
    let mut actions: Vec<i64> = (0..N as i64).map(|i| i % 5).collect();
    bencher.counter(ItemsCount::new(N)).bench_local(|| {
        for a in &mut actions {
            *a = (*a + 1) % 5;
        }
        venv.step_into(black_box(&actions), out.as_mut()).unwrap();
    });
}

#[divan::bench(args = [1, 2])]
fn vector_features(bencher: Bencher, threads: usize) {
    bench_batch(bencher, Config::features(), threads);
}

#[divan::bench(args = [1, 2])]
fn vector_gray_84x84(bencher: Bencher, threads: usize) {
    let config = Config { obs_type: ObsType::Grayscale, obs_size: (84, 84), ..Config::default() };
    bench_batch(bencher, config, threads);
}
