//! Incremental drawing equals a full redraw, bit for bit, on every frame of long random episodes under every
//! option that changes what is drawn: aliens and missiles, lives (the HUD's third field), frame stacking,
//! the HUD off, each HUD style (the gauges at every layout), small and odd sizes, RGB and gray.

use chopperscape::render::{Hud, HudScale, PixelFormat, Renderer};
use chopperscape::{ChopperScape, Config, Env, ObsType};

/// A tiny deterministic action source (xorshift), so the test needs no generator of its own.
struct Actions(u64);

impl Actions {
    fn next(&mut self) -> i64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % 5) as i64
    }
}

fn config(options: &[(&str, &str)]) -> Config {
    let mut c = Config::default();
    for (k, v) in options {
        c.set(k, v).unwrap();
    }
    c
}

/// Runs `steps` random steps (resetting after each episode) and compares, every frame, the incrementally drawn
/// frame with a full redraw, and the env's own pixel observation with the full redraw.
fn incremental_equals_full(options: &[(&str, &str)], steps: usize) {
    let config = config(options);
    let (h, w) = config.obs_size;
    let format = if config.obs_type == ObsType::Grayscale { PixelFormat::Gray } else { PixelFormat::Rgb };
    let k = config.frame_stack as usize;
    let scale = HudScale::of(&config);
    let mut env = ChopperScape::new(config.clone()).unwrap();
    let mut incremental = Renderer::with_look(h, w, Hud::of_observation(&config), config.look, format);
    let mut full = Renderer::with_look(h, w, Hud::of_observation(&config), config.look, format);
    let mut frame = vec![0u8; incremental.frame_len()];
    let mut expected = vec![0u8; full.frame_len()];
    let mut actions = Actions(0x9E37_79B9_7F4A_7C15);
    let mut obs = env.reset(Some(5)).0;
    incremental.draw_full(env.world(), scale, &mut frame);
    let (mut episodes, mut sprites_seen) = (1, 0);
    for t in 0..steps {
        full.draw_full(env.world(), scale, &mut expected);
        assert!(frame == expected, "{options:?}: step {t}: incremental frame differs from a full redraw");
        // The newest frame of the env's stacked observation is the same picture.
        let data = obs.as_u8().expect("u8 observation");
        let c = format.bytes_per_pixel();
        let same = if k == 1 {
            data == &expected[..]
        } else {
            data.chunks_exact(c * k).zip(expected.chunks_exact(c)).all(|(px, e)| &px[c * (k - 1)..] == e)
        };
        assert!(same, "{options:?}: step {t}: the env's observation differs from a full redraw");
        let wld = env.world();
        sprites_seen += wld.birds.len() + wld.fuel_tanks.len() + wld.aliens.len() + wld.missiles.len();
        let step = env.step(actions.next()).unwrap();
        obs = step.observation;
        if step.terminated || step.truncated {
            obs = env.reset(None).0;
            incremental.draw_full(env.world(), scale, &mut frame);
            episodes += 1;
        } else {
            incremental.draw(env.world(), scale, &mut frame);
        }
    }
    assert!(sprites_seen > steps, "{options:?}: too few sprites on screen to test anything");
    assert!(episodes > 1 || steps < 1000, "{options:?}: no episode ended in {steps} steps");
}

const BUSY: [(&str, &str); 4] =
    [("bird_prob", "0.1"), ("fuel_prob", "0.1"), ("alien_prob", "0.03"), ("max_fuel", "700")];

#[test]
fn incremental_equals_full_at_600x800_rgb_with_aliens() {
    incremental_equals_full(&BUSY, 120);
}

#[test]
fn incremental_equals_full_at_84x84_gray_with_lives_and_frame_stack() {
    let mut o = BUSY.to_vec();
    o.extend([("obs_type", "grayscale"), ("obs_size", "84x84"), ("lives", "3"), ("frame_stack", "4")]);
    incremental_equals_full(&o, 3000);
}

#[test]
fn incremental_equals_full_at_odd_97x131_rgb_with_lives() {
    let mut o = BUSY.to_vec();
    o.extend([("obs_size", "97x131"), ("lives", "4"), ("frame_stack", "2")]);
    incremental_equals_full(&o, 3000);
}

#[test]
fn incremental_equals_full_without_hud_at_odd_sizes() {
    for size in ["84x84", "13x211", "150x125"] {
        let mut o = BUSY.to_vec();
        o.extend([("obs_size", size), ("hud", "false"), ("bird_fuel_collision", "destroy")]);
        incremental_equals_full(&o, 1200);
    }
}

#[test]
fn incremental_equals_full_at_upscaled_gray_with_frame_skip_and_sticky_actions() {
    let mut o = BUSY.to_vec();
    o.extend([("obs_type", "grayscale"), ("obs_size", "640x880"), ("frame_skip", "3"), ("sticky_prob", "0.25")]);
    incremental_equals_full(&o, 100);
}

#[test]
fn incremental_equals_full_with_each_hud_style_at_every_layout() {
    // The text at 84 × 84 (pixel layout 1); the gauges at full size, with one row above the flight band (bars
    // side by side), with two, and stacked.
    for (size, style, lives) in
        [("84x84", "text", "3"), ("600x800", "gauge", "5"), ("12x40", "gauge", "2"), ("24x30", "gauge", "9")]
    {
        let mut o = BUSY.to_vec();
        o.extend([("obs_size", size), ("hud_style", style), ("lives", lives)]);
        incremental_equals_full(&o, if size == "600x800" { 150 } else { 1500 });
    }
    // Each look at agent resolution: the art (pixel layout 2) and the agent view, whose grown boxes overlap.
    for look in ["art", "agent"] {
        for size in ["84x84", "42x42", "16x16"] {
            let mut o = BUSY.to_vec();
            o.extend([("obs_size", size), ("look", look), ("obs_type", "grayscale")]);
            incremental_equals_full(&o, 1500);
        }
    }
}
