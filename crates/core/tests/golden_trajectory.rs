//! A golden trajectory, replayed bit for bit: seed, actions, and for every step the reward, flags, info and a
//! CRC-32 of the features observation's bytes. It pins the rules, the generator and the draw order on every machine.
//!
//! Regenerate (a change is a rules change, i.e. a new env version, and is reviewed like code):
//! `UPDATE_GOLDEN=1 cargo test -p chopperscape-core --test golden_trajectory`

use chopperscape::{ChopperScape, Config, Env, policy};
use std::fmt::Write;

/// Plays the golden episodes and prints one line per step.
fn trajectory(name: &str, config: Config, seed: u64, policy_name: &str) -> String {
    let mut out = String::new();
    let mut policy = policy::by_name(policy_name, seed, &config).unwrap();
    let mut env = ChopperScape::new(config).unwrap();
    let (obs, info) = env.reset(Some(seed));
    let bytes: Vec<u8> = obs.as_f32().unwrap().iter().flat_map(|v| v.to_le_bytes()).collect();
    writeln!(out, "# {name}: seed {seed}, policy {policy_name}").unwrap();
    writeln!(out, "reset fuel={} lives={} obs={:08x}", info.fuel, info.lives, crc32fast::hash(&bytes)).unwrap();
    loop {
        let action = policy.act(env.world()) as i64;
        let s = env.step(action).unwrap();
        let bytes: Vec<u8> = s.observation.as_f32().unwrap().iter().flat_map(|v| v.to_le_bytes()).collect();
        let cause = s.info.cause.map_or("-", |c| c.as_str());
        writeln!(
            out,
            "{action} {} {} {} fuel={} lives={} cause={cause} obs={:08x}",
            s.reward,
            s.terminated as u8,
            s.truncated as u8,
            s.info.fuel,
            s.info.lives,
            crc32fast::hash(&bytes)
        )
        .unwrap();
        if s.terminated || s.truncated {
            break;
        }
    }
    out
}

fn check(file: &str, actual: String) {
    let path = format!("{}/tests/golden/{file}", env!("CARGO_MANIFEST_DIR"));
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::write(&path, &actual).unwrap();
        return;
    }
    let expected =
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}; regenerate with UPDATE_GOLDEN=1"));
    for (i, (e, a)) in expected.lines().zip(actual.lines()).enumerate() {
        assert_eq!(e, a, "{file} line {} differs", i + 1);
    }
    assert_eq!(expected.lines().count(), actual.lines().count(), "{file}: length differs");
}

#[test]
fn v0_random_policy_replays_bit_for_bit() {
    check("trajectory_v0_random_seed42.txt", trajectory("v0", Config::features(), 42, "random"));
}

#[test]
fn every_option_replays_bit_for_bit() {
    let mut config = Config::features();
    for (k, v) in [
        ("lives", "3"),
        ("alien_prob", "0.02"),
        ("bird_fuel_collision", "destroy"),
        ("frame_skip", "2"),
        ("sticky_prob", "0.25"),
        ("bird_prob", "0.05"),
        ("fuel_prob", "0.03"),
        ("max_fuel", "400"),
        ("max_episode_steps", "600"),
    ] {
        config.set(k, v).unwrap();
    }
    check("trajectory_options_heuristic_seed7.txt", trajectory("all options", config, 7, "heuristic"));
}
