//! Golden frames: seeded states drawn and compared byte for byte with the PNG files in `tests/golden/`.
//!
//! Regenerate them (after a deliberate change to the art, the HUD or the scaling; review the images like code):
//!
//! ```sh
//! UPDATE_GOLDEN=1 cargo test -p chopperscape-core --test render_golden
//! ```

#![cfg(feature = "export")]

use std::path::PathBuf;

use chopperscape::export::write_png;
use chopperscape::render::{PixelFormat, Renderer};
use chopperscape::{ChopperScape, Config, Env, ObsType, World};

/// A frame to compare: its pixels, size and format.
struct Frame {
    pixels: Vec<u8>,
    height: u32,
    width: u32,
    format: PixelFormat,
}

fn golden_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden").join(format!("{name}.png"))
}

fn read_png(name: &str) -> Frame {
    let path = golden_path(name);
    let file = std::fs::File::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e}; regenerate with UPDATE_GOLDEN=1", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file)).read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut pixels).unwrap();
    pixels.truncate(info.buffer_size());
    let format = match info.color_type {
        png::ColorType::Rgb => PixelFormat::Rgb,
        png::ColorType::Grayscale => PixelFormat::Gray,
        other => panic!("{}: unexpected colour type {other:?}", path.display()),
    };
    Frame { pixels, height: info.height, width: info.width, format }
}

fn check(name: &str, frame: Frame) {
    let path = golden_path(name);
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        let mut bytes = Vec::new();
        write_png(&mut bytes, &frame.pixels, frame.height, frame.width, frame.format).unwrap();
        std::fs::write(&path, bytes).unwrap();
        return;
    }
    let want = read_png(name);
    assert_eq!((want.height, want.width, want.format), (frame.height, frame.width, frame.format), "{name}: size");
    if want.pixels != frame.pixels {
        let differ = want.pixels.iter().zip(&frame.pixels).filter(|(a, b)| a != b).count();
        let out = std::env::temp_dir().join(format!("{name}.actual.png"));
        let mut bytes = Vec::new();
        write_png(&mut bytes, &frame.pixels, frame.height, frame.width, frame.format).unwrap();
        std::fs::write(&out, bytes).unwrap();
        panic!("{name}: {differ} bytes differ from {}; this frame is in {}", path.display(), out.display());
    }
}

/// Steps a seeded env with a fixed action pattern until birds, tanks, an alien and a missile are all on screen.
fn busy_env(obs: &[(&str, &str)]) -> ChopperScape {
    let mut config = Config::default();
    for (k, v) in
        [("bird_prob", "0.2"), ("fuel_prob", "0.2"), ("alien_prob", "0.05"), ("lives", "50")].iter().chain(obs)
    {
        config.set(k, v).unwrap();
    }
    let mut env = ChopperScape::new(config).unwrap();
    env.reset(Some(11));
    for t in 0..400 {
        let w = env.world();
        if t > 30 && w.birds.len() >= 2 && !w.fuel_tanks.is_empty() && !w.aliens.is_empty() && !w.missiles.is_empty() {
            return env;
        }
        env.step([2, 4, 0, 4, 3, 4][t % 6]).unwrap();
    }
    panic!("seed 11 never showed every kind of sprite at once");
}

fn rgb_frame(env: &ChopperScape) -> Frame {
    Frame { pixels: env.render(), height: 600, width: 800, format: PixelFormat::Rgb }
}

#[test]
fn start_of_an_episode_matches_its_golden_frame() {
    let mut env = ChopperScape::new(Config::default()).unwrap();
    env.reset(Some(1));
    check("start", rgb_frame(&env));
}

#[test]
fn birds_tanks_an_alien_and_a_missile_match_their_golden_frame() {
    let env = busy_env(&[]);
    check("busy", rgb_frame(&env));
}

#[test]
fn hud_with_large_numbers_matches_its_golden_frame() {
    let mut world = World { fuel_left: 123_456, episode_return: -9_876_543, lives: 999, ..World::default() };
    world.chopper = chopperscape::Rect::placed(300, 250, chopperscape::consts::CHOPPER_SIZE);
    let mut renderer = Renderer::new(600, 800, true);
    let mut pixels = vec![0; renderer.frame_len()];
    renderer.draw_full(&world, 1000, &mut pixels);
    check("hud_large_numbers", Frame { pixels, height: 600, width: 800, format: PixelFormat::Rgb });
}

#[test]
fn grayscale_84x84_observation_matches_its_golden_frame() {
    let env = busy_env(&[("obs_type", "grayscale"), ("obs_size", "84x84")]);
    assert_eq!(env.config().obs_type, ObsType::Grayscale);
    let mut renderer = Renderer::with_format(84, 84, true, PixelFormat::Gray);
    let mut pixels = vec![0; renderer.frame_len()];
    renderer.draw_full(env.world(), env.config().lives, &mut pixels);
    check("gray_84x84", Frame { pixels, height: 84, width: 84, format: PixelFormat::Gray });
}

#[test]
fn odd_size_without_hud_matches_its_golden_frame() {
    let env = busy_env(&[("obs_size", "97x131"), ("hud", "false")]);
    let mut renderer = Renderer::new(97, 131, false);
    let mut pixels = vec![0; renderer.frame_len()];
    renderer.draw_full(env.world(), env.config().lives, &mut pixels);
    check("rgb_97x131_no_hud", Frame { pixels, height: 97, width: 131, format: PixelFormat::Rgb });
}
