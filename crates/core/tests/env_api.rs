//! The Gymnasium-shaped API: spaces, errors that change nothing, seeding, and snapshot bytes.

use chopperscape::{
    ACTION_MEANINGS, ChopperScape, Config, Dtype, Env, Error, ObsBufMut, ObsType, SNAPSHOT_VERSION, Snapshot,
    SnapshotError, features::FEATURES_LEN,
};

fn features_env() -> ChopperScape {
    ChopperScape::new(Config::features()).unwrap()
}

#[test]
fn spaces_declare_what_is_produced() {
    let mut env = features_env();
    assert_eq!(env.action_space().n, 5);
    assert_eq!(env.action_meanings(), ACTION_MEANINGS);
    assert_eq!(ACTION_MEANINGS, ["Right", "Left", "Down", "Up", "Do Nothing"]);
    let space = env.observation_space().clone();
    assert_eq!((space.shape.clone(), space.dtype), (vec![FEATURES_LEN], Dtype::F32));
    let (obs, info) = env.reset(Some(1));
    assert_eq!(obs.shape, space.shape);
    assert!(space.contains(obs.as_f32().unwrap()));
    assert_eq!((info.fuel, info.lives, info.cause), (1000, 1, None));
    let stacked = ChopperScape::new(Config { frame_stack: 4, ..Config::features() }).unwrap();
    assert_eq!(stacked.observation_space().shape, vec![FEATURES_LEN * 4]);
}

#[test]
fn invalid_action_is_an_error_naming_the_range_and_changes_nothing() {
    let mut env = features_env();
    env.reset(Some(3));
    let before = env.snapshot();
    for bad in [-1, 5, 99] {
        let err = env.step(bad).unwrap_err();
        assert_eq!(err, Error::InvalidAction(bad));
        assert!(err.to_string().contains("0..=4"));
    }
    assert_eq!(env.snapshot(), before);
}

#[test]
fn step_before_reset_and_after_the_end_are_errors() {
    let mut env = features_env();
    assert_eq!(env.step(0).unwrap_err(), Error::NotReset);
    let mut env = ChopperScape::new(Config { max_episode_steps: Some(2), ..Config::features() }).unwrap();
    env.reset(Some(0));
    env.step(4).unwrap();
    assert!(env.step(4).unwrap().truncated);
    let err = env.step(4).unwrap_err();
    assert!(matches!(err, Error::EpisodeOver(_)), "{err}");
    env.reset(None);
    assert!(env.step(4).is_ok(), "reset starts a new episode");
}

#[test]
fn a_buffer_of_the_wrong_size_or_type_is_refused_and_changes_nothing() {
    let mut env = features_env();
    env.reset(Some(0));
    let before = env.snapshot();
    let mut short = vec![0f32; FEATURES_LEN - 1];
    let err = env.step_into(0, ObsBufMut::F32(&mut short)).unwrap_err();
    assert!(err.to_string().contains(&FEATURES_LEN.to_string()), "{err}");
    let mut bytes = vec![0u8; FEATURES_LEN];
    assert!(matches!(env.step_into(0, ObsBufMut::U8(&mut bytes)), Err(Error::BufferSize { .. })));
    assert_eq!(env.snapshot(), before);
}

#[test]
fn unseeded_reset_continues_the_generator_stream() {
    let mut a = features_env();
    let mut b = features_env();
    a.reset(Some(10));
    b.reset(Some(10));
    for _ in 0..5 {
        assert_eq!(a.reset(None), b.reset(None));
    }
    let starts: std::collections::HashSet<_> = (0..20)
        .map(|_| {
            a.reset(None);
            a.world().chopper
        })
        .collect();
    assert!(starts.len() > 5, "unseeded resets must not repeat the same start");
}

#[test]
fn invalid_options_are_refused_at_construction() {
    let err = ChopperScape::new(Config { lives: 0, ..Config::features() }).unwrap_err();
    assert!(err.to_string().contains("lives") && err.to_string().contains("1..=1000"), "{err}");
    let err = ChopperScape::new(Config { sticky_prob: 1.5, ..Config::features() }).unwrap_err();
    assert!(err.to_string().contains("sticky_prob"), "{err}");
}

fn played_snapshot(config: Config) -> Snapshot {
    let mut env = ChopperScape::new(config).unwrap();
    env.reset(Some(5));
    for i in 0..120 {
        if env.step(i % 5).unwrap().terminated {
            break;
        }
    }
    env.snapshot()
}

#[test]
fn snapshot_bytes_round_trip_for_every_observation_type() {
    for obs_type in ObsType::ALL {
        let config = Config { obs_type, obs_size: (84, 84), frame_stack: 3, alien_prob: 0.05, ..Config::default() };
        let snap = played_snapshot(config.clone());
        let bytes = snap.to_bytes();
        assert_eq!(Snapshot::from_bytes(&bytes).unwrap(), snap, "{obs_type:?}");
        let mut a = ChopperScape::from_snapshot(&snap).unwrap();
        let mut b = ChopperScape::new(config).unwrap();
        b.restore(&Snapshot::from_bytes(&bytes).unwrap()).unwrap();
        for action in [0, 3, 3, 1, 2, 4] {
            if a.world().status.is_over() {
                break;
            }
            assert_eq!(a.step(action).unwrap(), b.step(action).unwrap(), "{obs_type:?}");
        }
    }
}

#[test]
fn truncated_snapshot_bytes_are_an_error_at_every_length() {
    let bytes = played_snapshot(Config { alien_prob: 0.05, ..Config::features() }).to_bytes();
    for len in 0..bytes.len() {
        let err = Snapshot::from_bytes(&bytes[..len]).unwrap_err();
        assert!(
            matches!(err, SnapshotError::Truncated(_) | SnapshotError::NotASnapshot | SnapshotError::Corrupted(_)),
            "len {len}: {err}"
        );
    }
}

#[test]
fn any_flipped_bit_is_detected() {
    let bytes = played_snapshot(Config::features()).to_bytes();
    for i in 0..bytes.len() {
        for bit in [0, 3, 7] {
            let mut b = bytes.clone();
            b[i] ^= 1 << bit;
            assert!(Snapshot::from_bytes(&b).is_err(), "flip of bit {bit} in byte {i} went unnoticed");
        }
    }
}

#[test]
fn foreign_bytes_and_other_versions_are_refused_by_name() {
    assert_eq!(Snapshot::from_bytes(b"GIF89a....").unwrap_err(), SnapshotError::NotASnapshot);
    let mut bytes = played_snapshot(Config::features()).to_bytes();
    bytes[4..6].copy_from_slice(&(SNAPSHOT_VERSION + 1).to_le_bytes());
    let err = Snapshot::from_bytes(&bytes).unwrap_err();
    assert!(err.to_string().contains(&format!("version {}", SNAPSHOT_VERSION + 1)), "{err}");
    assert!(err.to_string().contains(&format!("reads versions 1 to {SNAPSHOT_VERSION}")), "{err}");
    bytes[4..6].copy_from_slice(&0u16.to_le_bytes());
    assert!(matches!(Snapshot::from_bytes(&bytes), Err(SnapshotError::Version { found: 0, .. })));
}

#[test]
fn restoring_a_snapshot_with_other_options_is_refused_and_changes_nothing() {
    let snap = played_snapshot(Config { lives: 3, ..Config::features() });
    let mut env = features_env();
    env.reset(Some(1));
    let before = env.snapshot();
    let err = env.restore(&snap).unwrap_err();
    assert!(err.to_string().contains("other options"), "{err}");
    assert_eq!(env.snapshot(), before);
}

#[test]
fn a_snapshot_taken_before_the_first_reset_round_trips() {
    let env = features_env();
    let snap = Snapshot::from_bytes(&env.snapshot().to_bytes()).unwrap();
    let mut restored = ChopperScape::from_snapshot(&snap).unwrap();
    assert_eq!(restored.step(0).unwrap_err(), Error::NotReset);
}
