//! Rendering speed, single-threaded: whole `step_into` calls (rules, incremental drawing, the observation
//! written out to the caller's buffer), cycling through the actions and resetting when an episode ends.
//!
//! ```sh
//! cargo bench -p chopperscape-core --bench render
//! ```
//! Each line reports the time of one step; `items/s` is steps per second. Targets: `rgb_600x800` at least
//! 100,000 steps/s, `gray_84x84` at least 1,000,000 steps/s.

use chopperscape::render::{Hud, HudScale, PixelFormat, Renderer};
use chopperscape::{ChopperScape, Config, ObsBufMut};
use divan::Bencher;
use divan::counter::ItemsCount;

fn main() {
    divan::main();
}

/// An env with `options` and a buffer for its observations, reset with seed 0.
fn setup(options: &[(&str, &str)]) -> (ChopperScape, Vec<u8>, Vec<f32>) {
    let mut config = Config::default();
    for (k, v) in options {
        config.set(k, v).unwrap();
    }
    let mut env = ChopperScape::new(config).unwrap();
    let (mut bytes, mut floats) = (Vec::new(), Vec::new());
    let out = if env.observation_space().dtype == chopperscape::Dtype::U8 {
        bytes = vec![0u8; env.obs_len()];
        ObsBufMut::U8(&mut bytes)
    } else {
        floats = vec![0f32; env.obs_len()];
        ObsBufMut::F32(&mut floats)
    };
    env.reset_into(Some(0), out).unwrap();
    (env, bytes, floats)
}

use chopperscape::Env as _;

/// Steps `env` repeatedly with actions 0, 1, 2, 3, 4, 0, …, resetting at the end of each episode; with
/// `incremental`, through `step_into_incremental` (only what changed is drawn onto the caller's buffer).
fn bench_steps(bencher: Bencher, options: &[(&str, &str)], incremental: bool) {
    let (mut env, mut bytes, mut floats) = setup(options);
    let is_u8 = !bytes.is_empty();
    let mut t = 0i64;
    bencher.counter(ItemsCount::new(1usize)).bench_local(|| {
        t += 1;
        let out = if is_u8 { ObsBufMut::U8(&mut bytes) } else { ObsBufMut::F32(&mut floats) };
        let tr = if incremental { env.step_into_incremental(t % 5, out) } else { env.step_into(t % 5, out) }.unwrap();
        if tr.terminated || tr.truncated {
            let out = if is_u8 { ObsBufMut::U8(&mut bytes) } else { ObsBufMut::F32(&mut floats) };
            env.reset_into(None, out).unwrap();
        }
    });
}

/// `rgb` at 600 × 800, drawn onto the caller's buffer: the observation lands in the caller's memory without a
/// whole-frame copy.
#[divan::bench]
fn rgb_600x800_incremental(bencher: Bencher) {
    bench_steps(bencher, &[], true);
}

/// `grayscale` at 84 × 84, drawn onto the caller's buffer.
#[divan::bench]
fn gray_84x84_incremental(bencher: Bencher) {
    bench_steps(bencher, &[("obs_type", "grayscale"), ("obs_size", "84x84")], true);
}

/// `rgb` at 600 × 800 (the default): one step plus the 1.44 MB copy out.
#[divan::bench]
fn rgb_600x800(bencher: Bencher) {
    bench_steps(bencher, &[], false);
}

/// `grayscale` at 84 × 84: one step plus the 7 KB copy out.
#[divan::bench]
fn gray_84x84(bencher: Bencher) {
    bench_steps(bencher, &[("obs_type", "grayscale"), ("obs_size", "84x84")], false);
}

/// `grayscale` at 84 × 84 with the text HUD of pixel layout 1 instead of the gauges (`hud_style = "text"`).
#[divan::bench]
fn gray_84x84_text_hud(bencher: Bencher) {
    bench_steps(bencher, &[("obs_type", "grayscale"), ("obs_size", "84x84"), ("hud_style", "text")], false);
}

/// `grayscale` at 84 × 84 stacked 4 deep (the Atari-style setting).
#[divan::bench]
fn gray_84x84_stack4(bencher: Bencher) {
    bench_steps(bencher, &[("obs_type", "grayscale"), ("obs_size", "84x84"), ("frame_stack", "4")], false);
}

/// `rgb` at 84 × 84.
#[divan::bench]
fn rgb_84x84(bencher: Bencher) {
    bench_steps(bencher, &[("obs_size", "84x84")], false);
}

/// `rgb_float` at 84 × 84.
#[divan::bench]
fn rgb_float_84x84(bencher: Bencher) {
    bench_steps(bencher, &[("obs_type", "rgb_float"), ("obs_size", "84x84")], false);
}

/// The game alone, for reference: `features` observations, no pixels.
#[divan::bench]
fn features_only(bencher: Bencher) {
    let (mut env, _, mut floats) = setup(&[("obs_type", "features")]);
    let mut t = 0i64;
    bencher.counter(ItemsCount::new(1usize)).bench_local(|| {
        t += 1;
        let tr = env.step_into(t % 5, ObsBufMut::F32(&mut floats)).unwrap();
        if tr.terminated || tr.truncated {
            env.reset_into(None, ObsBufMut::F32(&mut floats)).unwrap();
        }
    });
}

/// A full redraw of a busy 600 × 800 frame (what `render()` costs), for comparison with the incremental step.
#[divan::bench]
fn draw_full_600x800(bencher: Bencher) {
    let mut env =
        ChopperScape::new(Config { alien_prob: 0.05, bird_prob: 0.2, lives: 50, ..Config::features() }).unwrap();
    env.reset(Some(11));
    for t in 0..60 {
        env.step(t % 5).unwrap();
    }
    let mut renderer = Renderer::with_format(600, 800, Hud::Text, PixelFormat::Rgb);
    let mut frame = vec![0u8; renderer.frame_len()];
    bencher.bench_local(|| renderer.draw_full(env.world(), HudScale::of(env.config()), &mut frame));
}

/// Copying 1.44 MB alone: the floor under `rgb_600x800`.
#[divan::bench]
fn memcpy_600x800x3(bencher: Bencher) {
    let src = vec![255u8; 600 * 800 * 3];
    let mut dst = vec![0u8; 600 * 800 * 3];
    bencher.counter(ItemsCount::new(1usize)).bench_local(|| dst.copy_from_slice(divan::black_box(&src)));
}
