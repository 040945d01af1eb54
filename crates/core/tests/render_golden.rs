//! Golden frames: seeded states drawn and compared byte for byte with the PNG files in `tests/golden/`.
//!
//! The small frames are the env's own observations (drawn incrementally through `step`). `gray_84x84`,
//! `rgb_84x84` and `gray_42x42` are pixel layout version 3 (`render::PIXELS_VERSION`: the agent view);
//! `gray_84x84_art` is version 2 (`look = "art"`) and `gray_84x84_text` version 1 (`look = "art"`,
//! `hud_style = "text"`): the older layouts stay selectable, and their frames stay what they were.
//!
//! Regenerate them (after a deliberate change to the art, the HUD or the scaling; review the images like code):
//!
//! ```sh
//! UPDATE_GOLDEN=1 cargo test -p chopperscape-core --test render_golden
//! ```

use std::path::PathBuf;

use chopperscape::render::{Hud, HudScale, PixelFormat, Renderer};
use chopperscape::{ChopperScape, Config, Env, Observation, World};

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

/// The frame as a PNG file's bytes (the core does no I/O and encodes no images: the CLI's `media/` records them;
/// this is the tests' own writer of golden files).
fn png_bytes(frame: &Frame) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, frame.width, frame.height);
    enc.set_color(match frame.format {
        PixelFormat::Rgb => png::ColorType::Rgb,
        PixelFormat::Gray => png::ColorType::Grayscale,
    });
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Fast);
    let mut w = enc.write_header().unwrap();
    w.write_image_data(&frame.pixels).unwrap();
    w.finish().unwrap();
    bytes
}

fn check(name: &str, frame: Frame) {
    let path = golden_path(name);
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::write(&path, png_bytes(&frame)).unwrap();
        return;
    }
    let want = read_png(name);
    assert_eq!((want.height, want.width, want.format), (frame.height, frame.width, frame.format), "{name}: size");
    if want.pixels != frame.pixels {
        let differ = want.pixels.iter().zip(&frame.pixels).filter(|(a, b)| a != b).count();
        let out = std::env::temp_dir().join(format!("{name}.actual.png"));
        std::fs::write(&out, png_bytes(&frame)).unwrap();
        panic!("{name}: {differ} bytes differ from {}; this frame is in {}", path.display(), out.display());
    }
}

/// Steps a seeded env with a fixed action pattern until birds, tanks, an alien and a missile are all on screen;
/// returns it with its last observation.
fn busy_env(obs: &[(&str, &str)]) -> (ChopperScape, Observation) {
    let mut config = Config::default();
    for (k, v) in
        [("bird_prob", "0.2"), ("fuel_prob", "0.2"), ("alien_prob", "0.05"), ("lives", "50")].iter().chain(obs)
    {
        config.set(k, v).unwrap();
    }
    let mut env = ChopperScape::new(config).unwrap();
    let mut last = env.reset(Some(11)).0;
    for t in 0..400 {
        let w = env.world();
        if t > 30 && w.birds.len() >= 2 && !w.fuel_tanks.is_empty() && !w.aliens.is_empty() && !w.missiles.is_empty() {
            return (env, last);
        }
        last = env.step([2, 4, 0, 4, 3, 4][t % 6]).unwrap().observation;
    }
    panic!("seed 11 never showed every kind of sprite at once");
}

/// A pixel observation (`u8`, `(H, W)` or `(H, W, 3)`) as a frame.
fn observation_frame(obs: Observation) -> Frame {
    let (height, width) = (obs.shape[0] as u32, obs.shape[1] as u32);
    let format = if obs.shape.len() == 2 { PixelFormat::Gray } else { PixelFormat::Rgb };
    Frame { pixels: obs.as_u8().expect("a u8 observation").to_vec(), height, width, format }
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
    let (env, _) = busy_env(&[("obs_type", "features")]);
    check("busy", rgb_frame(&env));
}

#[test]
fn hud_with_large_numbers_matches_its_golden_frame() {
    let mut world = World { fuel_left: 123_456, episode_return: -9_876_543, lives: 999, ..World::default() };
    world.chopper = chopperscape::Rect::placed(300, 250, chopperscape::consts::CHOPPER_SIZE);
    let mut renderer = Renderer::new(600, 800, Hud::Text);
    let mut pixels = vec![0; renderer.frame_len()];
    renderer.draw_full(&world, HudScale { max_fuel: 1000, max_lives: 1000 }, &mut pixels);
    check("hud_large_numbers", Frame { pixels, height: 600, width: 800, format: PixelFormat::Rgb });
}

#[test]
fn grayscale_84x84_observation_with_the_gauges_matches_its_golden_frame() {
    let (_, obs) = busy_env(&[("obs_type", "grayscale"), ("obs_size", "84x84")]);
    check("gray_84x84", observation_frame(obs));
}

#[test]
fn grayscale_42x42_agent_view_matches_its_golden_frame() {
    let (_, obs) = busy_env(&[("obs_type", "grayscale"), ("obs_size", "42x42")]);
    check("gray_42x42", observation_frame(obs));
}

#[test]
fn grayscale_84x84_with_the_art_matches_the_version_2_golden_frame() {
    // `look = "art"` draws pixel layout version 2: this file is the 84 × 84 golden frame of version 2.
    let (_, obs) = busy_env(&[("obs_type", "grayscale"), ("obs_size", "84x84"), ("look", "art")]);
    check("gray_84x84_art", observation_frame(obs));
}

#[test]
fn rgb_84x84_observation_with_the_gauges_matches_its_golden_frame() {
    let (_, obs) = busy_env(&[("obs_size", "84x84")]);
    check("rgb_84x84", observation_frame(obs));
}

#[test]
fn grayscale_84x84_with_the_text_hud_matches_the_version_1_golden_frame() {
    // `hud_style = "text"` draws pixel layout version 1: this file is the 84 × 84 golden frame of version 1.
    let options = [("obs_type", "grayscale"), ("obs_size", "84x84"), ("hud_style", "text"), ("look", "art")];
    let (_, obs) = busy_env(&options);
    check("gray_84x84_text", observation_frame(obs));
}

#[test]
fn full_size_render_with_the_gauges_matches_its_golden_frame() {
    let (env, _) = busy_env(&[("obs_type", "features"), ("hud_style", "gauge")]);
    check("gauge_600x800", rgb_frame(&env));
}

#[test]
fn odd_size_without_hud_matches_its_golden_frame() {
    let (_, obs) = busy_env(&[("obs_size", "97x131"), ("hud", "false"), ("look", "art")]);
    check("rgb_97x131_no_hud", observation_frame(obs));
}
