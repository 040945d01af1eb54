//! Sizes a batch cannot hold, and states it cannot be in, are refused up front with an error; a step moves
//! every environment or none.

use chopperscape::{ChopperScape, Config, ConfigError, Env, Error, ObsType, Snapshot};
use chopperscape_vector::{AutoresetMode, MAX_BATCH_BYTES, VectorEnv};

#[test]
fn batches_over_the_memory_budget_are_refused_without_allocating() {
    for n in [1usize << 40, 1 << 62, usize::MAX] {
        let err = VectorEnv::new(Config::features(), n, 1).unwrap_err();
        let msg = err.to_string();
        assert!(matches!(err, Error::Config(ConfigError::TooLarge { .. })), "{n}: {msg}");
        assert!(msg.contains(&n.to_string()) && msg.contains("budget of 16.0 GiB"), "{msg}");
    }
    let err = VectorEnv::new(Config::default(), 20_000, 1).unwrap_err().to_string();
    assert!(err.contains("num_envs=20000 environments") && err.contains("GiB"), "{err}");
}

#[test]
fn a_default_rgb_batch_of_64_costs_its_frames_not_bounds_per_element() {
    let frame = 600 * 800 * 3;
    let bytes = VectorEnv::batch_bytes(&Config::default(), 64, AutoresetMode::NextStep);
    // A canvas, an observation and an output observation per env, and a little state.
    assert!(bytes < 64 * (3 * frame + 64 * 1024), "{bytes}");
    assert!(bytes < MAX_BATCH_BYTES);
    let venv = VectorEnv::new(Config::default(), 64, 1).unwrap();
    assert!(matches!(venv.single_observation_space().bounds, chopperscape::Bounds::Uniform { .. }));
}

#[test]
fn thread_counts_out_of_range_are_refused_by_name() {
    let err = VectorEnv::new(Config::features(), 4, 100_000).unwrap_err().to_string();
    assert!(err.contains("num_threads") && err.contains("at most 1024"), "{err}");
}

fn short() -> Config {
    Config { max_fuel: 5, bird_prob: 0.0, fuel_prob: 0.0, ..Config::features() }
}

#[test]
fn states_the_batch_cannot_be_in_are_refused_and_change_nothing() {
    let mut venv = VectorEnv::new(short(), 2, 1).unwrap();
    venv.reset(Some(1)).unwrap();
    let mut ended = ChopperScape::new(short()).unwrap();
    ended.reset(Some(9));
    while !ended.step(4).unwrap().terminated {}
    let never = ChopperScape::new(short()).unwrap().snapshot();
    let before = (venv.env(0).snapshot(), venv.elapsed(0), venv.pending_reset(0));
    let cases: [(&Snapshot, bool, u32, &str); 4] = [
        (&ended.snapshot(), false, 5, "no reset is pending"),
        (&never, false, 0, "before any reset"),
        (&never, true, 0, "before any reset"),
        (&ended.snapshot(), true, 3, "elapsed steps 3"),
    ];
    for (snap, pending, elapsed, expect) in cases {
        let err = venv.restore_env(0, snap, pending, elapsed).unwrap_err().to_string();
        assert!(err.contains(expect) && err.contains("environment 0"), "{err}");
        assert_eq!((venv.env(0).snapshot(), venv.elapsed(0), venv.pending_reset(0)), before);
    }
    // The consistent version of the same state restores, and the next step resets that environment.
    venv.restore_env(0, &ended.snapshot(), true, 5).unwrap();
    venv.step(&[4, 4]).unwrap();
    assert_eq!(venv.fuel()[0], 5);
    assert_eq!(venv.rewards(), &[0.0, 1.0]);
}

#[test]
fn a_pending_reset_is_refused_in_same_step_mode() {
    let mut venv = VectorEnv::with_mode(short(), 1, 1, AutoresetMode::SameStep).unwrap();
    venv.reset(Some(1)).unwrap();
    let mut env = ChopperScape::new(short()).unwrap();
    env.reset(Some(2));
    while !env.step(4).unwrap().terminated {}
    let err = venv.restore_env(0, &env.snapshot(), true, 5).unwrap_err().to_string();
    assert!(err.contains("SAME_STEP"), "{err}");
}

/// CRC-32 (IEEE), to craft snapshot bytes as a hostile user would.
fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

#[test]
fn without_a_time_limit_a_step_count_of_u32_max_neither_truncates_nor_wraps() {
    let config = Config { max_episode_steps: None, bird_prob: 0.0, ..Config::features() };
    let mut env = ChopperScape::new(config.clone()).unwrap();
    env.reset(Some(4));
    env.step(4).unwrap();
    let bytes = env.snapshot().to_bytes();
    // Payload offsets of format version 3: return at 110, steps at 122 (see crates/core's snapshot tests).
    let mut payload = bytes[10..bytes.len() - 4].to_vec();
    let steps = u32::MAX - 1;
    payload[110..118].copy_from_slice(&i64::from(steps).to_le_bytes());
    payload[122..126].copy_from_slice(&steps.to_le_bytes());
    let mut crafted = bytes[..10].to_vec();
    crafted.extend_from_slice(&payload);
    crafted.extend_from_slice(&crc32(&payload).to_le_bytes());
    let snap = Snapshot::from_bytes(&crafted).unwrap();

    let mut venv = VectorEnv::new(config, 1, 1).unwrap();
    assert_eq!(venv.time_limit(), None);
    venv.reset(Some(0)).unwrap();
    venv.restore_env(0, &snap, false, steps).unwrap();
    for _ in 0..3 {
        venv.step(&[4]).unwrap();
        assert_eq!((venv.terminated()[0], venv.truncated()[0]), (false, false));
    }
    assert_eq!(venv.elapsed(0), u32::MAX);
}

#[test]
fn huge_observations_are_refused_by_the_env_budget_first() {
    let config = Config { obs_type: ObsType::Rgb, obs_size: (4096, 4096), frame_stack: 64, ..Config::default() };
    let err = VectorEnv::new(config, 2, 1).unwrap_err().to_string();
    assert!(err.contains("one environment's observation buffers") && err.contains("GiB"), "{err}");
}
