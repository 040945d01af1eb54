//! A batch behaves exactly as `num_envs` single environments: environment `i` of a batch seeded `s`
//! follows the single environment seeded `s + i`, across autoresets, for any thread count.

use chopperscape::{ChopperScape, Config, Env, ObsType, Observation};
use chopperscape_vector::{AutoresetMode, BatchError, Observations, VectorEnv, cause_code};

/// Short episodes (little fuel, many birds), so a few hundred steps hold many autoresets.
fn short_episodes(obs_type: ObsType) -> Config {
    Config {
        obs_type,
        obs_size: (16, 24),
        max_fuel: 40,
        bird_prob: 0.2,
        fuel_prob: 0.05,
        max_episode_steps: Some(30),
        ..Config::default()
    }
}

/// The action of environment `i` at step `t`: varied, deterministic.
fn action(i: usize, t: usize) -> i64 {
    ((i * 7 + t * 3 + t / 5) % 5) as i64
}

fn obs_of(obs: Observations<'_>, i: usize, len: usize) -> Observation {
    let shape = vec![len];
    match obs {
        Observations::U8(o) => {
            Observation { shape, data: chopperscape::ObsData::U8(o[i * len..(i + 1) * len].to_vec()) }
        }
        Observations::F32(o) => {
            Observation { shape, data: chopperscape::ObsData::F32(o[i * len..(i + 1) * len].to_vec()) }
        }
    }
}

fn flat(o: Observation) -> Observation {
    Observation { shape: vec![o.shape.iter().product()], data: o.data }
}

/// Steps a batch and single envs side by side with NEXT_STEP autoreset done by hand on the singles.
fn assert_batch_matches_singles(config: Config, num_envs: usize, threads: usize, seed: u64, steps: usize) {
    let mut venv = VectorEnv::new(config.clone(), num_envs, threads).unwrap();
    let len = venv.obs_len();
    let mut singles: Vec<ChopperScape> = (0..num_envs).map(|_| ChopperScape::new(config.clone()).unwrap()).collect();
    let mut ended = vec![false; num_envs];
    venv.reset(Some(seed)).unwrap();
    for (i, env) in singles.iter_mut().enumerate() {
        let (obs, info) = env.reset(Some(seed.wrapping_add(i as u64)));
        assert_eq!(obs_of(venv.observations(), i, len), flat(obs), "reset obs of env {i}");
        assert_eq!((venv.fuel()[i], venv.lives()[i]), (info.fuel, info.lives));
    }
    let mut episodes_ended = 0;
    for t in 0..steps {
        let actions: Vec<i64> = (0..num_envs).map(|i| action(i, t)).collect();
        venv.step(&actions).unwrap();
        for (i, env) in singles.iter_mut().enumerate() {
            let (obs, reward, term, trunc, info) = if ended[i] {
                let (obs, info) = env.reset(None);
                ended[i] = false;
                (obs, 0.0, false, false, info)
            } else {
                let s = env.step(actions[i]).unwrap();
                ended[i] = s.terminated || s.truncated;
                episodes_ended += usize::from(ended[i]);
                (s.observation, s.reward, s.terminated, s.truncated, s.info)
            };
            let at = format!("env {i}, step {t}");
            assert_eq!(obs_of(venv.observations(), i, len), flat(obs), "{at}");
            assert_eq!(venv.rewards()[i], reward, "{at}");
            assert_eq!((venv.terminated()[i], venv.truncated()[i]), (term, trunc), "{at}");
            assert_eq!((venv.fuel()[i], venv.lives()[i]), (info.fuel, info.lives), "{at}");
            assert_eq!(venv.causes()[i], cause_code(info.cause), "{at}");
        }
    }
    assert!(episodes_ended >= num_envs * 2, "only {episodes_ended} episodes ended: the test needs autoresets");
}

#[test]
fn env_i_follows_single_env_seeded_s_plus_i_across_autoresets() {
    for threads in [1, 2, 3] {
        for seed in [0, 7, u64::MAX - 2] {
            assert_batch_matches_singles(short_episodes(ObsType::Features), 5, threads, seed, 150);
        }
    }
}

#[test]
fn pixel_batches_match_single_envs_too() {
    for obs_type in [ObsType::Grayscale, ObsType::Rgb, ObsType::RgbFloat] {
        assert_batch_matches_singles(short_episodes(obs_type), 3, 2, 11, 80);
    }
    let stacked = Config { frame_stack: 3, ..short_episodes(ObsType::Grayscale) };
    assert_batch_matches_singles(stacked, 4, 2, 3, 80);
}

#[test]
fn more_threads_than_envs_is_fine() {
    assert_batch_matches_singles(short_episodes(ObsType::Features), 2, 8, 1, 100);
}

#[test]
fn same_step_resets_in_the_ending_step_and_keeps_the_final_observation() {
    same_step_matches_singles(ObsType::Features, false);
}

#[test]
fn persistent_caller_buffers_get_exact_incremental_frames() {
    for obs_type in [ObsType::Grayscale, ObsType::Rgb] {
        same_step_matches_singles(obs_type, true);
        same_step_matches_singles(obs_type, false);
    }
}

/// SAME_STEP batches into caller-owned buffers, checked against single envs step by step.
fn same_step_matches_singles(obs_type: ObsType, persistent: bool) {
    let config = Config { alien_prob: 0.05, lives: 2, ..short_episodes(obs_type) };
    let mut venv = VectorEnv::with_mode(config.clone(), 4, 2, AutoresetMode::SameStep).unwrap();
    venv.set_persistent_observations(persistent);
    let len = venv.obs_len();
    let mut buf = venv.new_buffers();
    venv.reset_into(Some(5), buf.as_mut()).unwrap();
    let mut singles: Vec<ChopperScape> = (0..4).map(|_| ChopperScape::new(config.clone()).unwrap()).collect();
    for (i, env) in singles.iter_mut().enumerate() {
        env.reset(Some(5 + i as u64));
    }
    let mut ended = 0;
    for t in 0..150 {
        let actions: Vec<i64> = (0..4).map(|i| action(i, t)).collect();
        let before = buf.clone();
        venv.step_into(&actions, buf.as_mut()).unwrap();
        for (i, env) in singles.iter_mut().enumerate() {
            let s = env.step(actions[i]).unwrap();
            let at = format!("env {i}, step {t}");
            assert_eq!((buf.rewards[i], buf.terminated[i], buf.truncated[i]), (s.reward, s.terminated, s.truncated));
            assert_eq!(
                (buf.fuel[i], buf.lives[i], buf.cause[i]),
                (s.info.fuel, s.info.lives, cause_code(s.info.cause))
            );
            let final_obs = obs_of(buf.final_observations().unwrap(), i, len);
            if s.terminated || s.truncated {
                ended += 1;
                assert_eq!(final_obs, flat(s.observation), "final obs, {at}");
                let (obs, _) = env.reset(None);
                assert_eq!(obs_of(buf.observations(), i, len), flat(obs), "reset obs, {at}");
            } else {
                assert_eq!(final_obs, obs_of(before.final_observations().unwrap(), i, len), "untouched, {at}");
                assert_eq!(obs_of(buf.observations(), i, len), flat(s.observation), "{at}");
            }
        }
    }
    assert!(ended >= 8, "only {ended} episodes ended: the test needs autoresets");
}

#[test]
fn invalid_actions_are_refused_and_change_no_env() {
    let mut venv = VectorEnv::new(short_episodes(ObsType::Features), 4, 2).unwrap();
    assert_eq!(venv.step(&[0; 4]), Err(BatchError::NotReset));
    venv.reset(Some(1)).unwrap();
    venv.step(&[0, 1, 2, 3]).unwrap();
    let worlds: Vec<_> = (0..4).map(|i| venv.env(i).world().clone()).collect();
    let obs = format!("{:?}", venv.observations());
    assert_eq!(venv.step(&[0, 1, 2]), Err(BatchError::ActionCount { expected: 4, got: 3 }));
    assert_eq!(venv.step(&[0, 1, 2, 5]), Err(BatchError::InvalidAction { index: 3, action: 5 }));
    let err = venv.step(&[0, -1, 2, 3]).unwrap_err().to_string();
    assert!(err.contains("-1") && err.contains("index 1") && err.contains("0..=4"), "{err}");
    let after: Vec<_> = (0..4).map(|i| venv.env(i).world().clone()).collect();
    assert_eq!(worlds, after, "a refused step moved an environment");
    assert_eq!(obs, format!("{:?}", venv.observations()), "a refused step wrote observations");
}

#[test]
fn wrong_buffers_and_counts_are_refused_with_what_was_expected() {
    let mut venv = VectorEnv::new(short_episodes(ObsType::Features), 3, 1).unwrap();
    let other = VectorEnv::new(short_episodes(ObsType::Features), 2, 1).unwrap();
    let mut small = other.new_buffers();
    let err = venv.reset_into(Some(0), small.as_mut()).unwrap_err().to_string();
    assert!(err.contains("observations") && err.contains(&(3 * venv.obs_len()).to_string()), "{err}");
    let pixels = VectorEnv::new(short_episodes(ObsType::Grayscale), 3, 1).unwrap();
    let mut u8s = pixels.new_buffers();
    assert!(matches!(venv.reset_into(Some(0), u8s.as_mut()), Err(BatchError::BufferSize { .. })));
    assert_eq!(
        venv.reset_seeds_into(&[Some(1)], venv.new_buffers().as_mut()),
        Err(BatchError::SeedCount { expected: 3, got: 1 })
    );
    let mut same = VectorEnv::with_mode(short_episodes(ObsType::Features), 3, 1, AutoresetMode::SameStep).unwrap();
    let mut plain = venv.new_buffers();
    same.reset_into(Some(0), plain.as_mut()).unwrap();
    assert_eq!(same.step_into(&[0; 3], plain.as_mut()), Err(BatchError::MissingFinalObservations));
    for (n, t) in [(0, 1), (1, 0)] {
        let err = VectorEnv::new(Config::features(), n, t).unwrap_err().to_string();
        assert!(err.contains(if n == 0 { "num_envs" } else { "num_threads" }) && err.contains(">= 1"), "{err}");
    }
    let err = VectorEnv::new(Config { lives: 0, ..Config::features() }, 2, 1).unwrap_err().to_string();
    assert!(err.contains("lives"), "{err}");
}

#[test]
fn per_env_seeds_and_unseeded_resets_follow_single_envs() {
    let config = short_episodes(ObsType::Features);
    let mut venv = VectorEnv::new(config.clone(), 3, 2).unwrap();
    let len = venv.obs_len();
    let mut buf = venv.new_buffers();
    venv.reset_seeds_into(&[Some(9), None, Some(100)], buf.as_mut()).unwrap();
    venv.reset_into(None, buf.as_mut()).unwrap();
    // Env 1 was never seeded: a core env starts from seed 0's stream.
    for (i, seed) in [Some(9), None, Some(100)].into_iter().enumerate() {
        let mut single = ChopperScape::new(config.clone()).unwrap();
        single.reset(seed);
        let (obs, _) = single.reset(None);
        assert_eq!(obs_of(buf.observations(), i, len), flat(obs), "env {i}");
    }
}

#[test]
fn a_batch_never_seeded_starts_as_if_seeded_zero() {
    let config = short_episodes(ObsType::Features);
    let (mut a, mut b) = (VectorEnv::new(config.clone(), 3, 1).unwrap(), VectorEnv::new(config, 3, 2).unwrap());
    a.reset(None).unwrap();
    b.reset(Some(0)).unwrap();
    assert_eq!(a.observations(), b.observations());
}

#[test]
fn time_limit_truncates_like_gymnasiums_time_limit_even_on_a_terminating_step() {
    // Fuel for exactly 12 steps and a limit of 12: step 12 both terminates (fuel) and reaches the limit.
    let config = Config { max_fuel: 12, bird_prob: 0.0, fuel_prob: 0.0, max_episode_steps: None, ..Config::features() };
    let mut venv = VectorEnv::new(config.clone(), 2, 1).unwrap();
    assert!(venv.set_time_limit(Some(0)).unwrap_err().to_string().contains("max_episode_steps"));
    venv.set_time_limit(Some(12)).unwrap();
    venv.reset(Some(0)).unwrap();
    for step in 1..=11 {
        venv.step(&[4, 4]).unwrap();
        assert_eq!((venv.terminated(), venv.truncated()), (&[false; 2][..], &[false; 2][..]), "step {step}");
    }
    venv.step(&[4, 4]).unwrap();
    assert_eq!((venv.terminated(), venv.truncated()), (&[true; 2][..], &[true; 2][..]));
    venv.step(&[4, 4]).unwrap(); // the reset step
    assert_eq!(venv.fuel(), &[12, 12]);
    // Without the limit the core alone reports only the termination.
    let mut plain = VectorEnv::new(config, 1, 1).unwrap();
    plain.reset(Some(0)).unwrap();
    for _ in 0..12 {
        plain.step(&[4]).unwrap();
    }
    assert_eq!((plain.terminated(), plain.truncated()), (&[true][..], &[false][..]));
}

#[test]
fn time_limit_counts_from_each_autoreset() {
    let config = Config { bird_prob: 0.0, fuel_prob: 0.0, max_episode_steps: None, ..Config::features() };
    let mut venv = VectorEnv::with_mode(config, 1, 1, AutoresetMode::SameStep).unwrap();
    venv.set_time_limit(Some(5)).unwrap();
    venv.reset(Some(3)).unwrap();
    let truncations: Vec<bool> = (0..15)
        .map(|_| {
            venv.step(&[4]).unwrap();
            venv.truncated()[0]
        })
        .collect();
    let expected: Vec<bool> = (1..=15).map(|t| t % 5 == 0).collect();
    assert_eq!(truncations, expected);
}

#[test]
fn a_batch_saved_and_restored_env_by_env_continues_identically() {
    let config = short_episodes(ObsType::Features);
    let mut venv = VectorEnv::new(config.clone(), 3, 2).unwrap();
    venv.set_time_limit(Some(30)).unwrap();
    venv.reset(Some(21)).unwrap();
    for t in 0..37 {
        venv.step(&[action(0, t), action(1, t), action(2, t)]).unwrap();
    }
    let mut copy = VectorEnv::new(config, 3, 1).unwrap();
    copy.set_time_limit(Some(30)).unwrap();
    for i in 0..3 {
        copy.restore_env(i, &venv.env(i).snapshot(), venv.pending_reset(i), venv.elapsed(i)).unwrap();
    }
    for t in 37..120 {
        let actions = [action(0, t), action(1, t), action(2, t)];
        venv.step(&actions).unwrap();
        copy.step(&actions).unwrap();
        assert_eq!(venv.observations(), copy.observations(), "step {t}");
        assert_eq!((venv.rewards(), venv.truncated()), (copy.rewards(), copy.truncated()), "step {t}");
    }
    let other = ChopperScape::new(Config { lives: 2, ..Config::features() }).unwrap();
    assert!(copy.restore_env(0, &other.snapshot(), false, 0).is_err());
}
