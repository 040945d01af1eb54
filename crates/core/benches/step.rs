//! Stepping speed with the `features` observation, single-threaded, through the allocation-free
//! `step_into` (resetting on episode end, as a trainer would).
//!
//! Run: `cargo bench -p chopperscape-core --bench step`. Target: ≥ 20 million steps/s on one core.

use chopperscape::{ChopperScape, Config, ObsBufMut, features::FEATURES_LEN, policy::RandomPolicy};
use divan::{Bencher, black_box, counter::ItemsCount};

fn main() {
    divan::main();
}

const STEPS: usize = 100_000;

/// Actions from the random policy, precomputed so the bench measures the env alone.
fn actions() -> Vec<i64> {
    use chopperscape::policy::Policy;
    let mut p = RandomPolicy::new(1);
    let w = chopperscape::World::default();
    (0..STEPS).map(|_| p.act(&w) as i64).collect()
}

fn run(bencher: Bencher, config: Config) {
    let actions = actions();
    let mut env = ChopperScape::new(config).unwrap();
    let mut obs = vec![0f32; env.obs_len()];
    env.reset_into(Some(0), ObsBufMut::F32(&mut obs)).unwrap();
    bencher.counter(ItemsCount::new(STEPS)).bench_local(|| {
        for &a in &actions {
            let t = env.step_into(a, ObsBufMut::F32(&mut obs)).unwrap();
            if t.terminated || t.truncated {
                env.reset_into(None, ObsBufMut::F32(&mut obs)).unwrap();
            }
        }
        black_box(&obs);
    });
}

#[divan::bench]
fn features(bencher: Bencher) {
    assert_eq!(FEATURES_LEN, 46);
    run(bencher, Config::features());
}

#[divan::bench]
fn features_all_options(bencher: Bencher) {
    let config = Config { lives: 3, alien_prob: 0.01, sticky_prob: 0.25, ..Config::features() };
    run(bencher, config);
}

/// The rules alone, for comparison: what the observation costs on top.
#[divan::bench]
fn rules_only(bencher: Bencher) {
    let actions: Vec<chopperscape::Action> =
        actions().into_iter().map(|a| chopperscape::Action::try_from(a).unwrap()).collect();
    let mut game = chopperscape::Game::new(Config::features()).unwrap();
    game.reset(Some(0));
    bencher.counter(ItemsCount::new(STEPS)).bench_local(|| {
        for &a in &actions {
            let o = game.step(a).unwrap();
            if o.terminated || o.truncated {
                game.reset(None);
            }
        }
    });
}
