//! The gauge HUD carries the state at agent resolution: a fixed decoder reads the fuel (within ±2 % of
//! `max_fuel`, in fact within half a unit of ink: 1/42,840 of it) and the lives (exactly) back from one
//! 84 × 84 frame, gray or RGB, for every level. The frames come from the env's own observations (stepped
//! through the public API) or from the public `Renderer` the env draws with, never from the gauge code directly.
//!
//! The decoder follows SPEC.md ("HUD and pixel layout"), written out here independently of the renderer.

use chopperscape::render::{Hud, HudScale, PIXELS_VERSION, PixelFormat, Renderer, TEXT_MIN_SIZE};
use chopperscape::{ChopperScape, Config, Env, HudStyle, Observation, Rect, World};

/// A frame: its pixels (one byte per channel), size and channels per pixel.
struct Frame<'a> {
    bytes: &'a [u8],
    width: usize,
    channels: usize,
}

impl Frame<'_> {
    /// The grey level of pixel `(x, y)`; asserts that RGB pixels of the HUD are grey.
    fn grey(&self, x: usize, y: usize) -> u8 {
        let at = (y * self.width + x) * self.channels;
        let px = &self.bytes[at..at + self.channels];
        assert!(px.iter().all(|&c| c == px[0]), "HUD pixel ({x}, {y}) is not grey: {px:?}");
        px[0]
    }
}

/// One bar of the layout: rows `[r0, r1)`, columns `[c0, c1)`.
type Bar = ((usize, usize), (usize, usize));

/// The fixed decoder's bars at 84 × 84: fuel in rows 1–3, lives in rows 5–6, all 84 columns.
const FUEL_84: Bar = ((1, 4), (0, 84));
const LIVES_84: Bar = ((5, 7), (0, 84));

/// The bars of an `h × w` frame by SPEC.md's formula (`None` below 10 rows).
fn layout(h: usize, w: usize) -> Option<(Bar, Bar)> {
    let b = 60 * h / 600;
    match b {
        0 => None,
        1 => Some((((0, 1), (0, w / 2)), ((0, 1), (w / 2, w)))),
        b => Some((((b / 8, b / 2), (0, w)), ((b / 2 + b / 8, b - b / 8), (0, w)))),
    }
}

/// Decodes one bar to the value it shows out of `max` from its first row alone: ink `I = Σ (255 − pixel)`,
/// value `I · max / (255 · columns)`.
fn decode_row(frame: &Frame<'_>, ((r0, _), (c0, c1)): Bar, max: u32) -> f64 {
    let (at, end) = ((r0 * frame.width + c0) * frame.channels, (r0 * frame.width + c1) * frame.channels);
    let ink: u64 = frame.bytes[at..end].iter().step_by(frame.channels).map(|&g| u64::from(255 - g)).sum();
    ink as f64 * f64::from(max) / (255.0 * (c1 - c0) as f64)
}

/// [`decode_row`], after checking that every pixel of the bar is grey and every row the same.
fn decode(frame: &Frame<'_>, ((r0, r1), (c0, c1)): Bar, max: u32) -> f64 {
    let row = |y: usize| (c0..c1).map(|x| frame.grey(x, y)).collect::<Vec<u8>>();
    let first = row(r0);
    for y in r0 + 1..r1 {
        assert_eq!(row(y), first, "row {y} of the bar differs from its first row");
    }
    let ink: u64 = first.iter().map(|&g| u64::from(255 - g)).sum();
    ink as f64 * f64::from(max) / (255.0 * (c1 - c0) as f64)
}

fn config(options: &[(&str, &str)]) -> Config {
    let mut c = Config::default();
    for (k, v) in options {
        c.set(k, v).unwrap();
    }
    c
}

/// The bytes of a pixel observation and its channels per pixel (`rgb_float` scaled back to bytes exactly).
fn pixels(obs: &Observation) -> (Vec<u8>, usize) {
    let channels = if obs.shape.len() == 3 { obs.shape[2] } else { 1 };
    let bytes = match (obs.as_u8(), obs.as_f32()) {
        (Some(b), _) => b.to_vec(),
        (_, Some(f)) => f.iter().map(|&x| (x * 255.0).round() as u8).collect(),
        _ => unreachable!(),
    };
    (bytes, channels)
}

/// Plays an episode without birds or tanks, doing nothing, so the fuel falls one level per underlying step
/// from `max_fuel` to 0; decodes every observation's fuel and lives. Returns how many observations were read.
fn fuel_decodes_through_an_episode(options: &[(&str, &str)], bars: (Bar, Bar)) -> usize {
    let mut all = vec![("bird_prob", "0"), ("fuel_prob", "0"), ("lives", "3")];
    all.extend_from_slice(options);
    let config = config(&all);
    let (max_fuel, lives) = (config.max_fuel, config.lives);
    let mut env = ChopperScape::new(config).unwrap();
    let (mut obs, mut info) = env.reset(Some(1));
    let mut seen = 0;
    loop {
        let (bytes, channels) = pixels(&obs);
        let frame = Frame { bytes: &bytes, width: obs.shape[1], channels };
        let fuel = decode(&frame, bars.0, max_fuel);
        let error = (fuel - f64::from(info.fuel)).abs();
        assert!(error <= 0.02 * f64::from(max_fuel), "{options:?}: fuel {} decoded as {fuel}", info.fuel);
        // The encoding is far finer than the ±2 % asked: half a unit of ink.
        let columns = (bars.0.1.1 - bars.0.1.0) as f64;
        assert!(error <= f64::from(max_fuel) / (510.0 * columns) + 1e-9, "{options:?}: fuel {} as {fuel}", info.fuel);
        assert_eq!(decode(&frame, bars.1, lives).round() as u32, info.lives, "{options:?}");
        seen += 1;
        let step = env.step(4).unwrap();
        (obs, info) = (step.observation, step.info);
        if step.terminated {
            assert_eq!(info.fuel, 0);
            let (bytes, channels) = pixels(&obs);
            let frame = Frame { bytes: &bytes, width: obs.shape[1], channels };
            assert_eq!(decode(&frame, bars.0, max_fuel), 0.0, "{options:?}: an empty tank is an empty bar");
            return seen + 1;
        }
    }
}

#[test]
fn the_pixel_layout_is_version_3_and_auto_draws_text_from_half_the_full_size() {
    assert_eq!(PIXELS_VERSION, 3);
    assert_eq!(TEXT_MIN_SIZE, (300, 400));
    let hud = |style, h, w| Hud::of(true, style, h, w);
    assert_eq!(hud(HudStyle::Auto, 600, 800), Hud::Text);
    assert_eq!(hud(HudStyle::Auto, 300, 400), Hud::Text);
    assert_eq!(hud(HudStyle::Auto, 299, 800), Hud::Gauge);
    assert_eq!(hud(HudStyle::Auto, 600, 399), Hud::Gauge);
    assert_eq!(hud(HudStyle::Auto, 84, 84), Hud::Gauge);
    assert_eq!(hud(HudStyle::Text, 84, 84), Hud::Text);
    assert_eq!(hud(HudStyle::Gauge, 600, 800), Hud::Gauge);
    assert_eq!(Hud::of(false, HudStyle::Gauge, 84, 84), Hud::Off);
    // render() keeps the text unless the gauges are asked for, whatever the observation.
    let small = config(&[("obs_size", "84x84"), ("hud", "false")]);
    assert_eq!(Hud::of_render(&small), Hud::Text);
    assert_eq!(Hud::of_render(&config(&[("hud_style", "gauge")])), Hud::Gauge);
}

#[test]
fn fuel_decodes_within_two_percent_at_every_level_of_the_default_tank_gray_and_rgb() {
    for obs_type in ["grayscale", "rgb", "rgb_float"] {
        let seen =
            fuel_decodes_through_an_episode(&[("obs_type", obs_type), ("obs_size", "84x84")], (FUEL_84, LIVES_84));
        assert_eq!(seen, 1001, "{obs_type}: every level 1000..=0 once");
    }
}

#[test]
fn fuel_decodes_within_two_percent_at_every_level_of_other_tanks() {
    for (max_fuel, skip) in [("1", "1"), ("37", "1"), ("4999", "1"), ("1000000", "997")] {
        for obs_type in ["grayscale", "rgb"] {
            let options = [("obs_type", obs_type), ("obs_size", "84x84"), ("max_fuel", max_fuel), ("frame_skip", skip)];
            let seen = fuel_decodes_through_an_episode(&options, (FUEL_84, LIVES_84));
            assert!(seen > 1, "{options:?}");
        }
    }
}

#[test]
fn fuel_and_lives_decode_at_other_sizes_by_the_documented_layout() {
    // 10 rows: one row above the flight band, the bars side by side; 20 rows: two rows; others as at 84 × 84.
    for size in ["10x8", "15x9", "20x13", "42x42", "64x48", "97x131", "210x160", "299x399"] {
        let (h, w) = size.split_once('x').unwrap();
        let bars = layout(h.parse().unwrap(), w.parse().unwrap()).unwrap();
        for obs_type in ["grayscale", "rgb"] {
            fuel_decodes_through_an_episode(&[("obs_type", obs_type), ("obs_size", size), ("max_fuel", "300")], bars);
        }
    }
    // The full-size frame with the gauges asked for.
    let bars = layout(600, 800).unwrap();
    fuel_decodes_through_an_episode(&[("obs_type", "grayscale"), ("hud_style", "gauge"), ("max_fuel", "50")], bars);
    assert_eq!(layout(9, 800), None);
}

/// Draws, with the renderer an 84 × 84 env of `format` uses, every lives value from `max_lives` down to 0
/// (incrementally, as steps do; every 50th frame checked against a full redraw) and decodes each.
fn lives_decode_exactly(format: PixelFormat, max_lives: u32, values: impl Iterator<Item = u32>) {
    let obs_type = if format == PixelFormat::Gray { "grayscale" } else { "rgb" };
    let config = config(&[("obs_type", obs_type), ("obs_size", "84x84"), ("lives", &max_lives.to_string())]);
    let scale = HudScale::of(&config);
    let mut renderer = Renderer::with_format(84, 84, Hud::of_observation(&config), format);
    let mut full = renderer.clone();
    let (mut frame, mut check) = (vec![0; renderer.frame_len()], vec![0; renderer.frame_len()]);
    let mut world =
        World { fuel_left: 500, lives: max_lives, chopper: Rect::placed(40, 100, (64, 64)), ..World::default() };
    renderer.draw_full(&world, scale, &mut frame);
    for (i, lives) in values.enumerate() {
        world.lives = lives;
        world.fuel_left = lives % 1001;
        renderer.draw(&world, scale, &mut frame);
        let f = Frame { bytes: &frame, width: 84, channels: format.bytes_per_pixel() };
        let decoded = if i % 50 == 0 { decode(&f, LIVES_84, max_lives) } else { decode_row(&f, LIVES_84, max_lives) };
        assert_eq!(decoded.round() as u32, lives, "{format:?}: {lives} of {max_lives} lives decoded as {decoded}");
        assert!((decoded - f64::from(lives)).abs() < 0.5 - 1e-6, "{lives} of {max_lives}: {decoded} is not clear");
        if i % 50 == 0 {
            full.draw_full(&world, scale, &mut check);
            assert!(frame == check, "{format:?}: {lives} of {max_lives}: incremental frame differs");
        }
    }
}

#[test]
fn lives_decode_exactly_for_every_allowed_value() {
    // Gray: every value of every `lives` option. RGB draws the same grey levels in each channel (checked on
    // every 50th frame): every value up to 64 lives and at 999 and 1000, the ends and middle elsewhere.
    for max_lives in 1..=1000 {
        lives_decode_exactly(PixelFormat::Gray, max_lives, (0..=max_lives).rev());
        if max_lives <= 64 || max_lives >= 999 {
            lives_decode_exactly(PixelFormat::Rgb, max_lives, (0..=max_lives).rev());
        } else {
            let values = [max_lives, max_lives - 1, max_lives / 2 + 1, max_lives / 2, max_lives / 3, 1, 0];
            lives_decode_exactly(PixelFormat::Rgb, max_lives, values.into_iter());
        }
    }
}

#[test]
fn lives_lost_to_birds_decode_from_the_envs_own_frames() {
    for obs_type in ["grayscale", "rgb"] {
        let options = [("obs_type", obs_type), ("obs_size", "84x84"), ("lives", "7"), ("bird_prob", "0.3")];
        let config = config(&options);
        let mut env = ChopperScape::new(config).unwrap();
        let (mut obs, mut info) = env.reset(Some(2));
        let mut values = std::collections::BTreeSet::new();
        let mut episodes = 0;
        for t in 0..5000 {
            let (bytes, channels) = pixels(&obs);
            let frame = Frame { bytes: &bytes, width: 84, channels };
            assert_eq!(decode(&frame, LIVES_84, 7).round() as u32, info.lives, "{obs_type}: step {t}");
            let fuel = decode(&frame, FUEL_84, 1000);
            assert!((fuel - f64::from(info.fuel)).abs() <= 20.0, "{obs_type}: step {t}: fuel {} as {fuel}", info.fuel);
            values.insert(info.lives);
            if env.world().status.is_over() {
                (obs, info) = env.reset(None);
                episodes += 1;
            } else {
                let step = env.step([4, 4, 3, 2][t % 4]).unwrap();
                (obs, info) = (step.observation, step.info);
            }
        }
        assert!(episodes > 2, "{obs_type}: {episodes} episodes");
        assert_eq!(values.len(), 8, "{obs_type}: every lives value 7..=0 seen: {values:?}");
    }
}
