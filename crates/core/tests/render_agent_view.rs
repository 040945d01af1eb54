//! The agent view (pixel layout version 3, SPEC.md "The agent view"): at 84 × 84 and 42 × 42, and at the
//! smallest sizes, every kind of entity is a solid box at its own grey level, at least 3 × 3 pixels, on the
//! white sky; `look = "auto"` picks it below half the full size and the art from there up. The expected boxes are
//! computed here from SPEC's sizes and scaling, independently of the renderer.

use chopperscape::consts::{ALIEN_SIZE, BIRD_SIZE, CHOPPER_SIZE, FUEL_TANK_SIZE, MISSILE_SIZE};
use chopperscape::render::{AGENT_GREYS, AGENT_MIN_SIDE, Hud, HudScale, PixelFormat, Renderer};
use chopperscape::{Alien, ChopperScape, Config, Env, Look, Rect, World};

/// SPEC's grey levels, written out: tank, bird, alien, missile, chopper.
const GREYS: [u8; 5] = [176, 0, 32, 64, 112];

/// One entity of each kind, apart from each other, in drawing order (tank, bird, alien, missile, chopper).
fn world() -> (World, [Rect; 5]) {
    let rects = [
        Rect::placed(120, 400, FUEL_TANK_SIZE),
        Rect::placed(600, 150, BIRD_SIZE),
        Rect::placed(500, 300, ALIEN_SIZE),
        Rect::placed(360, 460, MISSILE_SIZE),
        Rect::placed(100, 100, CHOPPER_SIZE),
    ];
    let world = World {
        fuel_tanks: vec![rects[0]],
        birds: vec![rects[1]],
        aliens: vec![Alien { body: rects[2], age: 0 }],
        missiles: vec![rects[3]],
        chopper: rects[4],
        ..World::default()
    };
    (world, rects)
}

/// The box SPEC gives an entity in an `h × w` frame: its corner scaled down, its size scaled and rounded, grown
/// to 3 pixels a side about its centre (within the flight band).
fn expected_box(r: &Rect, h: usize, w: usize) -> (usize, usize, usize, usize) {
    let round = |len: i32, frame: usize, full: usize| ((2 * len as usize * frame + full) / (2 * full)).max(1);
    let (sw, sh) = (round(r.w, w, 800), round(r.h, h, 600));
    let (bw, bh) = (sw.max(3).min(w), sh.max(3).min(h));
    let (x, y) = (r.x as usize * w / 800, r.y as usize * h / 600);
    let top = 60 * h / 600;
    (x.saturating_sub((bw - sw) / 2), y.saturating_sub((bh - sh) / 2).max(top.min(y)), bw, bh)
}

#[test]
fn every_kind_is_a_solid_box_at_its_grey_level_and_at_least_3x3() {
    assert_eq!(AGENT_GREYS, GREYS);
    assert_eq!(AGENT_MIN_SIDE, 3);
    let (world, rects) = world();
    for (h, w) in [(84, 84), (42, 42), (64, 48), (21, 28)] {
        for format in [PixelFormat::Gray, PixelFormat::Rgb] {
            let c = format.bytes_per_pixel();
            let mut r = Renderer::with_look(h as u32, w as u32, Hud::Off, Look::Agent, format);
            let mut frame = vec![0; r.frame_len()];
            r.draw_full(&world, HudScale::default(), &mut frame);
            let mut expected = vec![255u8; h * w];
            for (k, rect) in rects.iter().enumerate() {
                let (x, y, bw, bh) = expected_box(rect, h, w);
                assert!(bw >= 3 && bh >= 3, "{h}x{w}: kind {k} is {bw}x{bh}");
                for yy in y..(y + bh).min(h) {
                    expected[yy * w + x..(yy * w + x + bw).min(yy * w + w)].fill(GREYS[k]);
                }
            }
            for (i, &want) in expected.iter().enumerate() {
                let px = &frame[i * c..(i + 1) * c];
                assert!(
                    px.iter().all(|&v| v == want),
                    "{h}x{w} {format:?}: pixel ({}, {}) is {px:?}, not {want}",
                    i % w,
                    i / w
                );
            }
            // The sky stays white and every kind is at least 79 levels darker than it.
            assert!(GREYS.iter().all(|&g| 255 - g >= 79));
        }
    }
}

#[test]
fn look_auto_shows_the_agent_view_below_half_the_full_size_and_the_art_from_there() {
    assert_eq!(Look::Auto.at(84, 84), Look::Agent);
    assert_eq!(Look::Auto.at(42, 42), Look::Agent);
    assert_eq!(Look::Auto.at(299, 800), Look::Agent);
    assert_eq!(Look::Auto.at(300, 400), Look::Art);
    assert_eq!(Look::Auto.at(600, 800), Look::Art);
    assert_eq!(Look::Art.at(84, 84), Look::Art);
    assert_eq!(Look::Agent.at(600, 800), Look::Agent);
    assert_eq!(Config::default().look, Look::Auto);
}

/// The env's observations under `look = "auto"` at 84 × 84 are the agent view, and under `"art"` the art, each
/// equal to the renderer of that look drawing the env's world.
#[test]
fn the_env_draws_the_look_it_is_given() {
    for (look, drawn) in [("auto", Look::Agent), ("agent", Look::Agent), ("art", Look::Art)] {
        for size in ["84x84", "42x42"] {
            let mut config = Config::default();
            for (k, v) in [("obs_type", "grayscale"), ("obs_size", size), ("look", look), ("bird_prob", "0.2")] {
                config.set(k, v).unwrap();
            }
            let (h, w) = config.obs_size;
            let mut env = ChopperScape::new(config.clone()).unwrap();
            env.reset(Some(3));
            let mut obs = env.step(4).unwrap().observation;
            for _ in 0..60 {
                obs = env.step(0).unwrap().observation;
            }
            let mut r = Renderer::with_look(h, w, Hud::of_observation(&config), drawn, PixelFormat::Gray);
            let mut frame = vec![0; r.frame_len()];
            r.draw_full(env.world(), HudScale::of(&config), &mut frame);
            assert!(obs.as_u8().unwrap() == &frame[..], "look {look} at {size}");
        }
    }
}
