//! `step_into_incremental` draws only what changed onto the caller's buffer; every frame must equal the frame
//! `step_into` copies out, whatever the options, sizes, buffer switches, mixing of the two calls, and restores.

use chopperscape::{ChopperScape, Config, ObsBufMut, ObsType, policy::Policy, policy::RandomPolicy};

fn config(obs_type: ObsType, size: (u32, u32), extra: &[(&str, &str)]) -> Config {
    let mut c = Config { obs_type, obs_size: size, ..Config::default() };
    for (k, v) in extra {
        c.set(k, v).unwrap();
    }
    c
}

/// Plays `steps` random steps with two envs: `copying` uses `step_into`, `drawing` `step_into_incremental`
/// onto `buffers[i % buffers.len()]` switched every `switch_every` steps; asserts every frame is equal.
fn check(config: Config, steps: usize, switch_every: usize, buffers: usize) {
    let mut copying = ChopperScape::new(config.clone()).unwrap();
    let mut drawing = ChopperScape::new(config).unwrap();
    let n = copying.obs_len();
    let mut expected = vec![0u8; n];
    let mut bufs = vec![vec![0u8; n]; buffers];
    copying.reset_into(Some(11), ObsBufMut::U8(&mut expected)).unwrap();
    drawing.reset_into(Some(11), ObsBufMut::U8(&mut bufs[0])).unwrap();
    let mut policy = RandomPolicy::new(3);
    for i in 0..steps {
        let a = policy.act(copying.world()) as i64;
        let which = (i / switch_every) % buffers;
        let t1 = copying.step_into(a, ObsBufMut::U8(&mut expected)).unwrap();
        let t2 = drawing.step_into_incremental(a, ObsBufMut::U8(&mut bufs[which])).unwrap();
        assert_eq!(t1, t2);
        assert!(bufs[which] == expected, "frame {i} differs");
        if t1.terminated || t1.truncated {
            copying.reset_into(None, ObsBufMut::U8(&mut expected)).unwrap();
            drawing.reset_into(None, ObsBufMut::U8(&mut bufs[which])).unwrap();
            assert!(bufs[which] == expected, "reset after frame {i} differs");
        }
    }
}

#[test]
fn incremental_rgb_full_size_equals_copied_frames() {
    check(
        config(ObsType::Rgb, (600, 800), &[("bird_prob", "0.05"), ("alien_prob", "0.02"), ("lives", "3")]),
        400,
        1000,
        1,
    );
}

#[test]
fn incremental_gray_small_and_odd_sizes_equal_copied_frames() {
    let extra = [("bird_prob", "0.1"), ("fuel_prob", "0.05"), ("alien_prob", "0.03"), ("lives", "2")];
    check(config(ObsType::Grayscale, (84, 84), &extra), 1500, 10_000, 1);
    check(config(ObsType::Rgb, (97, 131), &extra), 1500, 10_000, 1);
}

#[test]
fn switching_buffers_redraws_in_full() {
    let extra = [("bird_prob", "0.1"), ("alien_prob", "0.03")];
    check(config(ObsType::Grayscale, (84, 84), &extra), 600, 7, 3);
}

#[test]
fn other_observation_types_behave_as_step_into() {
    for (t, size) in [(ObsType::Features, (600, 800)), (ObsType::RgbFloat, (40, 50))] {
        let c = Config { obs_type: t, obs_size: size, ..Config::default() };
        let mut a = ChopperScape::new(c.clone()).unwrap();
        let mut b = ChopperScape::new(c).unwrap();
        let mut x = vec![0f32; a.obs_len()];
        let mut y = vec![0f32; b.obs_len()];
        a.reset_into(Some(2), ObsBufMut::F32(&mut x)).unwrap();
        b.reset_into(Some(2), ObsBufMut::F32(&mut y)).unwrap();
        for i in 0..100 {
            a.step_into(i % 5, ObsBufMut::F32(&mut x)).unwrap();
            b.step_into_incremental(i % 5, ObsBufMut::F32(&mut y)).unwrap();
            assert_eq!(x, y);
        }
    }
    let c = Config { obs_type: ObsType::Grayscale, obs_size: (30, 40), frame_stack: 3, ..Config::default() };
    let mut a = ChopperScape::new(c.clone()).unwrap();
    let mut b = ChopperScape::new(c).unwrap();
    let mut x = vec![0u8; a.obs_len()];
    let mut y = vec![0u8; b.obs_len()];
    a.reset_into(Some(2), ObsBufMut::U8(&mut x)).unwrap();
    b.reset_into(Some(2), ObsBufMut::U8(&mut y)).unwrap();
    for i in 0..100 {
        a.step_into(i % 5, ObsBufMut::U8(&mut x)).unwrap();
        b.step_into_incremental(i % 5, ObsBufMut::U8(&mut y)).unwrap();
        assert_eq!(x, y, "frame stack {i}");
    }
}

#[test]
fn mixing_calls_and_restoring_snapshots_stay_exact() {
    let c = config(ObsType::Grayscale, (84, 84), &[("bird_prob", "0.1"), ("alien_prob", "0.03")]);
    let mut env = ChopperScape::new(c.clone()).unwrap();
    let mut reference = ChopperScape::new(c).unwrap();
    let mut buf = vec![0u8; env.obs_len()];
    let mut expected = vec![0u8; env.obs_len()];
    env.reset_into(Some(4), ObsBufMut::U8(&mut buf)).unwrap();
    reference.reset_into(Some(4), ObsBufMut::U8(&mut expected)).unwrap();
    let mut snap = None;
    for i in 0..400i64 {
        let a = (i * 7 + i / 3) % 5;
        if i == 150 {
            snap = Some(env.snapshot());
        }
        if i == 250 {
            // Jump both back to step 150: the drawn buffer no longer matches the renderer's state.
            env.restore(snap.as_ref().unwrap()).unwrap();
            reference.restore(snap.as_ref().unwrap()).unwrap();
        }
        let t = if i % 3 == 0 {
            env.step_into(a, ObsBufMut::U8(&mut buf)).unwrap()
        } else {
            env.step_into_incremental(a, ObsBufMut::U8(&mut buf)).unwrap()
        };
        let r = reference.step_into(a, ObsBufMut::U8(&mut expected)).unwrap();
        assert_eq!(t, r);
        assert!(buf == expected, "step {i}");
        if t.terminated || t.truncated {
            break;
        }
    }
}
