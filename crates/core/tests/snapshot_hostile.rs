//! Crafted snapshots with a correct checksum: sizes are checked before anything is allocated, and every value
//! is checked against what the rules can reach, so a decoded snapshot is always a state the game could be in.

use chopperscape::{
    ChopperScape, Config, Env, Error, HudStyle, Look, ObsType, SNAPSHOT_VERSION, Snapshot, SnapshotError,
};

/// Payload offsets of the version-3 format (see `snapshot.rs`).
const OBS_TYPE: usize = 0;
const OBS_H: usize = 1;
const OBS_W: usize = 5;
const FRAME_STACK: usize = 9;
const HUD_STYLE: usize = 14;
const LOOK: usize = 15;
const MAX_EPISODE_STEPS: usize = 61;
const CHOPPER: usize = 98;
const FUEL: usize = 106;
const RETURN: usize = 110;
const LIVES_LEFT: usize = 118;
const STEPS: usize = 122;
const STATUS: usize = 126;
const BIRDS: usize = 127;
const HEADER: usize = 10;

/// Edits the payload of `bytes` and writes the matching checksum, as a hostile user would.
fn tamper(bytes: &[u8], edit: impl FnOnce(&mut Vec<u8>)) -> Vec<u8> {
    let mut payload = bytes[HEADER..bytes.len() - 4].to_vec();
    edit(&mut payload);
    let mut out = bytes[..HEADER - 4].to_vec();
    out.extend_from_slice(&(payload.len() as u32).to_le_bytes());
    out.extend_from_slice(&payload);
    out.extend_from_slice(&crc32fast_hash(&payload).to_le_bytes());
    out
}

/// CRC-32 (IEEE), bitwise: the tests need no dependency for it.
fn crc32fast_hash(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

fn put(p: &mut [u8], at: usize, v: &[u8]) {
    p[at..at + v.len()].copy_from_slice(v);
}

fn played(config: Config, steps: usize) -> ChopperScape {
    let mut env = ChopperScape::new(config).unwrap();
    env.reset(Some(3));
    for i in 0..steps {
        if env.step((i % 5) as i64).unwrap().terminated {
            break;
        }
    }
    env
}

fn corrupted(bytes: &[u8]) -> String {
    match Snapshot::from_bytes(bytes) {
        Err(e @ SnapshotError::Corrupted(_)) => e.to_string(),
        other => panic!("expected a corrupted-snapshot error, got {other:?}"),
    }
}

#[test]
fn the_own_checksum_helper_matches_the_encoder() {
    let bytes = played(Config::features(), 10).snapshot().to_bytes();
    assert_eq!(tamper(&bytes, |_| {}), bytes);
}

#[test]
fn a_small_snapshot_asking_for_a_huge_observation_is_refused_before_allocating() {
    let bytes = ChopperScape::new(Config::features()).unwrap().snapshot().to_bytes();
    assert!(bytes.len() < 200);
    let huge = tamper(&bytes, |p| {
        p[OBS_TYPE] = ObsType::RgbFloat as u8;
        put(p, OBS_H, &4096u32.to_le_bytes());
        put(p, OBS_W, &4096u32.to_le_bytes());
        put(p, FRAME_STACK, &64u32.to_le_bytes());
    });
    let err = corrupted(&huge);
    assert!(err.contains("budget") && err.contains("GiB"), "{err}");
    // Within the budget, the frame stack's length is checked against the options before it is read.
    let big = tamper(&bytes, |p| {
        p[OBS_TYPE] = ObsType::Rgb as u8;
        put(p, OBS_H, &1024u32.to_le_bytes());
        put(p, OBS_W, &1024u32.to_le_bytes());
        put(p, FRAME_STACK, &8u32.to_le_bytes());
    });
    let err = corrupted(&big);
    assert!(err.contains("holds 0 values") || err.contains("observation type"), "{err}");
}

#[test]
fn counters_that_would_wrap_or_that_no_episode_reaches_are_refused() {
    let env = played(Config { max_episode_steps: None, ..Config::features() }, 30);
    let bytes = env.snapshot().to_bytes();
    let steps_max = tamper(&bytes, |p| put(p, STEPS, &u32::MAX.to_le_bytes()));
    assert!(corrupted(&steps_max).contains("cannot have burnt") || corrupted(&steps_max).contains("return"));
    let ret_max = tamper(&bytes, |p| put(p, RETURN, &i64::MAX.to_le_bytes()));
    assert!(corrupted(&ret_max).contains("return"), "{}", corrupted(&ret_max));
    let ret_low = tamper(&bytes, |p| put(p, RETURN, &(-1i64).to_le_bytes()));
    assert!(corrupted(&ret_low).contains("return"));
    let fuel = tamper(&bytes, |p| put(p, FUEL, &0u32.to_le_bytes()));
    assert!(corrupted(&fuel).contains("fuel"), "{}", corrupted(&fuel));
    let lives = tamper(&bytes, |p| put(p, LIVES_LEFT, &0u32.to_le_bytes()));
    assert!(corrupted(&lives).contains("lives"), "{}", corrupted(&lives));
    let over = tamper(&bytes, |p| put(p, STATUS, &[4]));
    assert!(corrupted(&over).contains("truncated"), "{}", corrupted(&over));
    let limit = tamper(&bytes, |p| put(p, MAX_EPISODE_STEPS, &10u32.to_le_bytes()));
    assert!(corrupted(&limit).contains("max_episode_steps"), "{}", corrupted(&limit));
}

#[test]
fn entities_off_their_paths_or_out_of_order_are_refused() {
    let config = Config { bird_prob: 1.0, fuel_prob: 1.0, alien_prob: 1.0, lives: 1000, ..Config::features() };
    let env = played(config, 60);
    let w = env.world();
    assert!(w.birds.len() > 2 && w.aliens.len() > 2 && w.fuel_tanks.len() > 2 && !w.missiles.is_empty());
    let bytes = env.snapshot().to_bytes();
    let bird_x = |p: &mut Vec<u8>, x: i32| put(p, BIRDS + 4, &x.to_le_bytes());
    assert!(corrupted(&tamper(&bytes, |p| bird_x(p, 700))).contains("bird"));
    let last = w.birds.last().unwrap().x;
    assert!(corrupted(&tamper(&bytes, |p| bird_x(p, last))).contains("order"));
    let alien_age = BIRDS + 4 + 8 * w.birds.len() + 4 + 8 * w.fuel_tanks.len() + 4 + 8;
    assert!(corrupted(&tamper(&bytes, |p| put(p, alien_age, &7u32.to_le_bytes()))).contains("alien"));
    // Far outside the band, where `x + w` would overflow an i32 (found by the fuzzer).
    let far = tamper(&bytes, |p| put(p, CHOPPER, &(i32::MAX - 10).to_le_bytes()));
    assert!(corrupted(&far).contains("outside the flight band"), "{}", corrupted(&far));
    let huge_count = tamper(&bytes, |p| put(p, BIRDS, &10_000u32.to_le_bytes()));
    assert!(corrupted(&huge_count).contains("at most"));
}

#[test]
fn non_finite_or_impossible_values_in_a_frame_stack_are_refused() {
    for obs_type in [ObsType::Features, ObsType::RgbFloat] {
        let config = Config { obs_type, obs_size: (16, 16), frame_stack: 2, ..Config::default() };
        let bytes = played(config, 5).snapshot().to_bytes();
        let last = bytes.len() - 4 - 4; // the last f32 of the stack, before the checksum
        for bad in [f32::NAN, f32::INFINITY, 2.0, -3.0] {
            let b = tamper(&bytes, |p| {
                let at = last - HEADER;
                put(p, at, &bad.to_le_bytes());
            });
            assert!(corrupted(&b).contains("frame stack"), "{obs_type:?} {bad}: {}", corrupted(&b));
        }
    }
    let bytes =
        played(Config { obs_type: ObsType::RgbFloat, obs_size: (8, 8), frame_stack: 2, ..Config::default() }, 3)
            .snapshot()
            .to_bytes();
    let b = tamper(&bytes, |p| {
        let at = p.len() - 4;
        put(p, at, &0.5f32.to_le_bytes()); // not a byte over 255
    });
    assert!(corrupted(&b).contains("frame stack"));
}

#[test]
fn a_never_reset_snapshot_must_be_the_initial_state() {
    let bytes = ChopperScape::new(Config::features()).unwrap().snapshot().to_bytes();
    Snapshot::from_bytes(&bytes).unwrap();
    let moved = tamper(&bytes, |p| put(p, STEPS, &3u32.to_le_bytes()));
    assert!(corrupted(&moved).contains("never-reset"));
}

#[test]
fn every_state_of_long_random_episodes_under_every_option_decodes() {
    let configs = [
        Config { alien_prob: 0.2, bird_prob: 0.3, fuel_prob: 0.2, lives: 5, frame_skip: 3, ..Config::features() },
        Config {
            alien_prob: 0.3,
            bird_prob: 0.5,
            fuel_prob: 0.5,
            lives: 50,
            sticky_prob: 0.25,
            bird_fuel_collision: chopperscape::BirdFuelCollision::Destroy,
            max_fuel: 30,
            max_episode_steps: Some(400),
            frame_stack: 3,
            ..Config::features()
        },
        Config {
            obs_type: ObsType::RgbFloat,
            obs_size: (12, 16),
            frame_stack: 2,
            alien_prob: 0.1,
            ..Config::default()
        },
    ];
    for config in configs {
        let mut env = ChopperScape::new(config).unwrap();
        let mut seed = 0;
        env.reset(Some(seed));
        for i in 0..3000u64 {
            let snap = env.snapshot();
            let decoded = Snapshot::from_bytes(&snap.to_bytes());
            assert_eq!(decoded.as_ref(), Ok(&snap), "step {i}");
            let s = env.step((i * 7 % 5) as i64).unwrap();
            if s.terminated || s.truncated {
                assert!(Snapshot::from_bytes(&env.snapshot().to_bytes()).is_ok(), "ended at step {i}");
                seed += 1;
                env.reset(Some(seed));
            }
        }
    }
}

#[test]
fn a_refused_restore_names_the_options_that_differ() {
    let snap = played(Config { lives: 3, ..Config::features() }, 5).snapshot();
    let mut env = ChopperScape::new(Config { max_episode_steps: None, ..Config::features() }).unwrap();
    let err = env.restore(&snap).unwrap_err().to_string();
    assert!(err.contains("lives 3 != 1") && err.contains("max_episode_steps 10000 != none"), "{err}");
    assert!(!err.contains("Config {") && !err.contains("obs_type"), "{err}");
}

#[test]
fn a_step_counter_at_u32_max_saturates_instead_of_wrapping_or_truncating() {
    // A state with the counter at its top, as an episode without a step limit reaches after 2^32 - 1 steps
    // (refuelling all the way): the next steps neither wrap the counter nor truncate the episode.
    let config = Config { max_episode_steps: None, bird_prob: 0.0, ..Config::features() };
    let env = played(config, 1);
    let bytes = env.snapshot().to_bytes();
    let top = tamper(&bytes, |p| {
        put(p, STEPS, &(u32::MAX - 1).to_le_bytes());
        put(p, RETURN, &i64::from(u32::MAX - 1).to_le_bytes());
    });
    let mut env = ChopperScape::from_snapshot(&Snapshot::from_bytes(&top).unwrap()).unwrap();
    for _ in 0..3 {
        let s = env.step(4).unwrap();
        assert!(!s.truncated && !s.terminated);
    }
    assert_eq!(env.world().steps, u32::MAX);
    assert_eq!(env.world().episode_return, i64::from(u32::MAX - 1) + 3);
}

#[test]
fn an_unknown_hud_style_is_refused_by_name() {
    let bytes = played(Config::features(), 10).snapshot().to_bytes();
    assert_eq!(bytes[HEADER + HUD_STYLE], HudStyle::Auto as u8);
    let err = corrupted(&tamper(&bytes, |p| p[HUD_STYLE] = 3));
    assert!(err.contains("hud_style"), "{err}");
}

#[test]
fn an_unknown_look_is_refused_by_name() {
    let bytes = played(Config::features(), 10).snapshot().to_bytes();
    assert_eq!(bytes[HEADER + LOOK], Look::Auto as u8);
    let err = corrupted(&tamper(&bytes, |p| p[LOOK] = 3));
    assert!(err.contains("look"), "{err}");
}

/// `bytes` (version 3) rewritten in the version-2 format: no `look` byte.
fn as_version_2(bytes: &[u8]) -> Vec<u8> {
    let mut v2 = tamper(bytes, |p| {
        p.remove(LOOK);
    });
    v2[4..6].copy_from_slice(&2u16.to_le_bytes());
    v2
}

/// `bytes` (version 3) rewritten in the version-1 format: no `hud_style` and no `look` byte.
fn as_version_1(bytes: &[u8]) -> Vec<u8> {
    let mut v1 = tamper(bytes, |p| {
        p.remove(LOOK);
        p.remove(HUD_STYLE);
    });
    v1[4..6].copy_from_slice(&1u16.to_le_bytes());
    v1
}

/// Takes a snapshot of an env of `options` played 40 steps, rewrites it in an older format (`older`), and checks
/// that it decodes to the same options, that it re-encodes into the current format, that the restored env
/// continues exactly as the original (stacked frames included), and that an env where `option` has its default refuses it naming `refusal`.
fn older_snapshot_loads_as_drawn(
    options: &[(&str, &str)],
    older: fn(&[u8]) -> Vec<u8>,
    default: impl FnOnce(Config) -> Config,
    refusal: &str,
) {
    let mut config = Config::default();
    for (k, v) in options {
        config.set(k, v).unwrap();
    }
    let mut original = played(config.clone(), 40);
    let snap = Snapshot::from_bytes(&older(&original.snapshot().to_bytes())).unwrap();
    assert_eq!(snap.config(), &config);
    // Written again, it is in the current format, and that round-trips (the fuzz target checks the same).
    let upgraded = snap.to_bytes();
    assert_eq!(upgraded[4..6], SNAPSHOT_VERSION.to_le_bytes());
    let again = Snapshot::from_bytes(&upgraded).unwrap();
    assert_eq!(again, snap);
    assert_eq!(again.to_bytes(), upgraded);
    let mut restored = ChopperScape::from_snapshot(&snap).unwrap();
    for t in 0..30 {
        let (a, b) = (original.step(t % 5).unwrap(), restored.step(t % 5).unwrap());
        assert_eq!(a, b, "step {t}");
        if a.terminated {
            break;
        }
    }
    let mut other = ChopperScape::new(default(config)).unwrap();
    match other.restore(&snap) {
        Err(Error::Snapshot(SnapshotError::ConfigMismatch(m))) => assert!(m.contains(refusal), "{m}"),
        other => panic!("expected a refusal naming {refusal}, got {other:?}"),
    }
}

#[test]
fn version_2_snapshots_load_with_the_art_they_were_drawn_with() {
    assert_eq!(SNAPSHOT_VERSION, 3);
    let options = [("obs_type", "grayscale"), ("obs_size", "84x84"), ("frame_stack", "2"), ("look", "art")];
    // An env of the default look (the agent view at 84 × 84) refuses it by name.
    older_snapshot_loads_as_drawn(&options, as_version_2, |c| Config { look: Look::Auto, ..c }, "look art != auto");
}

#[test]
fn version_1_snapshots_load_with_the_text_hud_they_were_drawn_with() {
    let options = [
        ("obs_type", "grayscale"),
        ("obs_size", "84x84"),
        ("frame_stack", "3"),
        ("hud_style", "text"),
        ("look", "art"),
    ];
    assert_eq!(
        Snapshot::from_bytes(&as_version_1(&played(Config::features(), 5).snapshot().to_bytes()))
            .unwrap()
            .config()
            .hud_style,
        HudStyle::Text
    );
    // An env of the default style refuses it by name.
    let auto = |c: Config| Config { hud_style: HudStyle::Auto, ..c };
    older_snapshot_loads_as_drawn(&options, as_version_1, auto, "hud_style text != auto");
}
