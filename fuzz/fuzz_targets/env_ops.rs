//! Arbitrary options and arbitrary sequences of operations (reset, step with any action, snapshot and
//! restore) on the env: nothing panics, invalid input is an error, and the invariants of the rules hold.
#![no_main]
use arbitrary::Arbitrary;
use chopperscape::{ChopperScape, Config, Env, OPTION_NAMES};
use libfuzzer_sys::fuzz_target;

#[derive(Arbitrary, Debug)]
enum Op {
    Reset(Option<u64>),
    Step(i64),
    SnapshotRestore,
}

#[derive(Arbitrary, Debug)]
struct Input {
    options: Vec<(u8, String)>,
    small_pixels: bool,
    ops: Vec<Op>,
}

fuzz_target!(|input: Input| {
    let mut config = Config::features();
    if input.small_pixels {
        config.obs_type = chopperscape::ObsType::Grayscale;
        config.obs_size = (16, 16);
    }
    for (name, value) in input.options.iter().take(8) {
        let name = OPTION_NAMES[*name as usize % OPTION_NAMES.len()];
        if name == "obs_size" {
            continue; // keep frames small so the fuzzer stays fast
        }
        let before = config.clone();
        if config.set(name, value).is_err() {
            assert_eq!(config, before, "a refused option changes nothing");
        }
    }
    let Ok(mut env) = ChopperScape::new(config) else { return };
    for op in input.ops.iter().take(2000) {
        match op {
            Op::Reset(seed) => {
                env.reset(*seed);
            }
            Op::Step(a) => {
                let _ = env.step(*a);
            }
            Op::SnapshotRestore => {
                let snap = chopperscape::Snapshot::from_bytes(&env.snapshot().to_bytes()).expect("own bytes decode");
                env.restore(&snap).expect("same options");
            }
        }
        let w = env.world();
        assert!(w.chopper.in_band() || w.status == chopperscape::Status::NotStarted);
        assert!(w.birds.iter().chain(&w.fuel_tanks).chain(&w.missiles).all(|r| r.in_band()));
        assert!(w.fuel_left <= env.config().max_fuel);
    }
});
