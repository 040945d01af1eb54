//! Property tests: for any seed, options and actions, the invariants of the rules hold, two envs with the same
//! seed and actions stay identical, and a restored snapshot continues identically.

use chopperscape::{BirdFuelCollision, ChopperScape, Config, Env, ObsType, Snapshot, Status};
use proptest::prelude::*;

fn any_config() -> impl Strategy<Value = Config> {
    (
        1u32..4,
        any::<bool>(),
        prop_oneof![Just(0.0), 0.0..0.2f64],
        1u32..4,
        prop_oneof![Just(0.0), 0.0..1.0f64],
        prop_oneof![Just(0.01), 0.0..0.3f64],
        prop_oneof![Just(0.01), 0.0..0.3f64],
        prop_oneof![Just(1000u32), 1u32..200],
        prop_oneof![Just(Some(10_000u32)), (1u32..300).prop_map(Some), Just(None)],
        1u32..3,
    )
        .prop_map(|(lives, destroy, alien, skip, sticky, bird, fuel, max_fuel, max_steps, stack)| Config {
            obs_type: ObsType::Features,
            frame_stack: stack,
            lives,
            bird_fuel_collision: if destroy { BirdFuelCollision::Destroy } else { BirdFuelCollision::Pass },
            alien_prob: alien,
            frame_skip: skip,
            sticky_prob: sticky,
            bird_prob: bird,
            fuel_prob: fuel,
            max_fuel,
            max_episode_steps: max_steps,
            ..Config::default()
        })
}

fn check_invariants(env: &ChopperScape) {
    let w = env.world();
    let c = env.config();
    assert!(w.chopper.in_band(), "{:?}", w.chopper);
    assert!(w.birds.iter().chain(&w.fuel_tanks).chain(&w.missiles).all(|r| r.in_band()));
    assert!(w.aliens.iter().all(|a| a.body.in_band()));
    assert!(w.fuel_left <= c.max_fuel);
    assert!(w.lives <= c.lives);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn invariants_hold_and_same_seed_same_trajectory(
        config in any_config(),
        seed in any::<u64>(),
        actions in proptest::collection::vec(0i64..5, 1..400),
    ) {
        let mut a = ChopperScape::new(config.clone()).unwrap();
        let mut b = ChopperScape::new(config.clone()).unwrap();
        let (oa, ia) = a.reset(Some(seed));
        let (ob, ib) = b.reset(Some(seed));
        prop_assert_eq!(oa, ob);
        prop_assert_eq!(ia, ib);
        for &action in &actions {
            let sa = a.step(action).unwrap();
            let sb = b.step(action).unwrap();
            check_invariants(&a);
            // Each underlying step pays +1 or −10; an agent step holds 1..=frame_skip of them.
            let r = sa.reward as i64;
            prop_assert_eq!(r as f32, sa.reward);
            let sums = (1..=config.frame_skip as i64).any(|n| (n - r) % 11 == 0 && (0..=n).contains(&((n - r) / 11)));
            prop_assert!(sums, "reward {} with frame_skip {}", sa.reward, config.frame_skip);
            prop_assert!(a.observation_space().contains(sa.observation.as_f32().unwrap()));
            prop_assert_eq!(&sa, &sb);
            prop_assert_eq!(a.world(), b.world());
            if sa.terminated || sa.truncated {
                prop_assert!(a.world().status.is_over());
                break;
            }
        }
    }

    #[test]
    fn a_restored_snapshot_continues_identically(
        config in any_config(),
        seed in any::<u64>(),
        before in proptest::collection::vec(0i64..5, 0..150),
        after in proptest::collection::vec(0i64..5, 1..150),
    ) {
        let mut env = ChopperScape::new(config.clone()).unwrap();
        env.reset(Some(seed));
        for &a in &before {
            if env.world().status.is_over() { break; }
            env.step(a).unwrap();
        }
        let snap = env.snapshot();
        let decoded = Snapshot::from_bytes(&snap.to_bytes()).unwrap();
        prop_assert_eq!(&decoded, &snap);
        let mut restored = ChopperScape::new(config).unwrap();
        restored.restore(&decoded).unwrap();
        for &a in &after {
            if env.world().status != Status::Running { break; }
            let x = env.step(a).unwrap();
            let y = restored.step(a).unwrap();
            prop_assert_eq!(x, y);
        }
        prop_assert_eq!(env.world(), restored.world());
    }
}
