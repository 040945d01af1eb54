//! The pixel observations: grayscale is the luma of rgb, rgb_float is rgb / 255, every observation lies in its
//! declared space, the HUD and the sprites land where SPEC.md puts them, and drawing is deterministic.

use chopperscape::consts::{BIRD_SIZE, CHOPPER_SIZE, FUEL_TANK_SIZE};
use chopperscape::render::{Hud, HudScale, PixelFormat, Renderer};
use chopperscape::{ChopperScape, Config, Dtype, Env, Rect, World, luma};

fn config(options: &[(&str, &str)]) -> Config {
    let mut c = Config::default();
    for (k, v) in
        [("bird_prob", "0.1"), ("fuel_prob", "0.1"), ("alien_prob", "0.03"), ("lives", "3")].iter().chain(options)
    {
        c.set(k, v).unwrap();
    }
    c
}

/// Observations of `steps` steps of seed 9 with actions cycling 0..5 (reset observation first).
fn run(options: &[(&str, &str)], steps: usize) -> (ChopperScape, Vec<chopperscape::Observation>) {
    let mut env = ChopperScape::new(config(options)).unwrap();
    let mut out = vec![env.reset(Some(9)).0];
    for t in 0..steps {
        let s = env.step((t % 5) as i64).unwrap();
        out.push(s.observation);
        if s.terminated || s.truncated {
            out.push(env.reset(None).0);
        }
    }
    (env, out)
}

#[test]
fn grayscale_equals_the_luma_of_rgb_at_every_step() {
    for size in ["600x800", "84x84", "97x131"] {
        let (_, rgb) = run(&[("obs_size", size)], 150);
        let (_, gray) = run(&[("obs_size", size), ("obs_type", "grayscale")], 150);
        assert_eq!(rgb.len(), gray.len());
        for (i, (c, g)) in rgb.iter().zip(&gray).enumerate() {
            let want: Vec<u8> = c.as_u8().unwrap().chunks_exact(3).map(|p| luma(p[0], p[1], p[2])).collect();
            assert!(g.as_u8().unwrap() == &want[..], "{size}: observation {i}: grayscale is not luma(rgb)");
        }
    }
}

#[test]
fn luma_is_the_documented_integer_bt601_formula() {
    assert_eq!(luma(255, 255, 255), 255);
    assert_eq!(luma(0, 0, 0), 0);
    assert_eq!(luma(255, 0, 0), 76); // (299·255 + 500) / 1000 = 76.745
    assert_eq!(luma(0, 255, 0), 150); // 149.685 + 0.5
    assert_eq!(luma(0, 0, 255), 29); // 29.07 + 0.5
    assert_eq!(luma(38, 110, 215), 100); // (11362 + 64570 + 24510 + 500) / 1000 = 100.942
}

#[test]
fn rgb_float_equals_rgb_divided_by_255_with_frame_stack() {
    let (_, rgb) = run(&[("obs_size", "84x84"), ("frame_stack", "3")], 200);
    let (_, float) = run(&[("obs_size", "84x84"), ("frame_stack", "3"), ("obs_type", "rgb_float")], 200);
    for (c, f) in rgb.iter().zip(&float) {
        assert_eq!(c.shape, f.shape);
        let (c, f) = (c.as_u8().unwrap(), f.as_f32().unwrap());
        assert!(c.iter().zip(f).all(|(&b, &x)| x == b as f32 / 255.0));
    }
}

#[test]
fn observations_have_the_declared_shape_and_lie_in_the_declared_space() {
    type Case<'a> = (&'a [(&'a str, &'a str)], Vec<usize>, Dtype);
    let cases: [Case; 6] = [
        (&[], vec![600, 800, 3], Dtype::U8),
        (&[("obs_type", "rgb_float"), ("obs_size", "84x84")], vec![84, 84, 3], Dtype::F32),
        (&[("obs_type", "grayscale"), ("obs_size", "84x84")], vec![84, 84], Dtype::U8),
        (&[("obs_type", "grayscale"), ("obs_size", "84x84"), ("frame_stack", "4")], vec![84, 84, 4], Dtype::U8),
        (&[("obs_size", "97x131"), ("frame_stack", "2")], vec![97, 131, 6], Dtype::U8),
        (&[("obs_type", "rgb_float"), ("obs_size", "33x44"), ("frame_stack", "2")], vec![33, 44, 6], Dtype::F32),
    ];
    for (options, shape, dtype) in cases {
        let (env, obs) = run(options, 60);
        let space = env.observation_space();
        assert_eq!((&space.shape, space.dtype), (&shape, dtype), "{options:?}");
        for o in &obs {
            assert_eq!(o.shape, shape, "{options:?}");
            match dtype {
                Dtype::U8 => assert!(space.contains(o.as_u8().unwrap()), "{options:?}"),
                Dtype::F32 => assert!(space.contains(o.as_f32().unwrap()), "{options:?}"),
            }
        }
    }
}

#[test]
fn reset_fills_the_stack_with_the_first_frame_and_steps_shift_it() {
    let (_, obs) = run(&[("obs_type", "grayscale"), ("obs_size", "84x84"), ("frame_stack", "3")], 2);
    let (_, single) = run(&[("obs_type", "grayscale"), ("obs_size", "84x84")], 2);
    let frame = |o: &chopperscape::Observation, j: usize| -> Vec<u8> {
        o.as_u8().unwrap().iter().skip(j).step_by(3).copied().collect()
    };
    let s = |i: usize| single[i].as_u8().unwrap().to_vec();
    assert_ne!(s(0), s(2), "the chopper moved");
    assert_eq!([frame(&obs[0], 0), frame(&obs[0], 1), frame(&obs[0], 2)], [s(0), s(0), s(0)]);
    assert_eq!([frame(&obs[2], 0), frame(&obs[2], 1), frame(&obs[2], 2)], [s(0), s(1), s(2)]);
}

#[test]
fn render_gives_the_full_frame_with_the_hud_whatever_the_observation() {
    let (env, _) = run(&[("obs_type", "grayscale"), ("obs_size", "84x84"), ("hud", "false")], 30);
    let frame = env.render();
    assert_eq!(frame.len(), 600 * 800 * 3);
    let mut expected = vec![0; frame.len()];
    Renderer::new(600, 800, Hud::Text).draw_full(env.world(), HudScale::of(env.config()), &mut expected);
    assert!(frame == expected);
    let mut into = vec![7; frame.len()];
    env.render_into(&mut into).unwrap();
    assert!(into == frame);
    assert!(env.render_into(&mut [0; 10]).is_err());
}

/// The pixel `(x, y)` of an RGB frame of width 800.
fn px(frame: &[u8], x: usize, y: usize) -> [u8; 3] {
    let i = (y * 800 + x) * 3;
    [frame[i], frame[i + 1], frame[i + 2]]
}

#[test]
fn hud_text_is_black_starts_at_x_10_and_sits_on_the_baseline_y_20() {
    let world = World { fuel_left: 1000, chopper: Rect::placed(50, 100, CHOPPER_SIZE), ..World::default() };
    let mut r = Renderer::new(600, 800, Hud::Text);
    let mut frame = vec![0; r.frame_len()];
    r.draw_full(&world, HudScale::default(), &mut frame);
    let ink: Vec<(usize, usize)> =
        (0..60).flat_map(|y| (0..800).map(move |x| (x, y))).filter(|&(x, y)| px(&frame, x, y) == [0, 0, 0]).collect();
    assert!(ink.len() > 500, "the HUD line has ink");
    assert_eq!(ink.iter().map(|p| p.0).min(), Some(10), "left end at x = 10");
    // Capitals ("F") end on the row above the baseline; only descenders go below it.
    assert!(px(&frame, 10, 19) == [0, 0, 0] && px(&frame, 10, 20) != [0, 0, 0]);
    assert!(ink.iter().all(|&(_, y)| (6..22).contains(&y)));
    // Everything else above the band is white.
    assert!((0..60).all(|y| (0..800).all(|x| ink.contains(&(x, y)) || px(&frame, x, y) == [255; 3])));
}

#[test]
fn hud_shows_lives_only_with_more_than_one_life_and_can_be_turned_off() {
    let chopper = Rect::placed(50, 100, CHOPPER_SIZE);
    let world = World { fuel_left: 5, episode_return: 7, lives: 2, chopper, ..World::default() };
    let ink_right_of = |frame: &[u8], x0: usize| (6..22).any(|y| (x0..800).any(|x| px(frame, x, y) == [0; 3]));
    let draw = |hud: Hud, lives: u32| {
        let mut f = vec![0; 600 * 800 * 3];
        Renderer::new(600, 800, hud).draw_full(&world, HudScale { max_fuel: 1000, max_lives: lives }, &mut f);
        f
    };
    // "Fuel Left: 5 | Rewards: 7" is 25 characters of 16 px: it ends at x = 410.
    assert!(!ink_right_of(&draw(Hud::Text, 1), 410));
    assert!(ink_right_of(&draw(Hud::Text, 2), 410));
    assert!(draw(Hud::Off, 2).iter().take(60 * 800 * 3).all(|&b| b == 255));
}

#[test]
fn sprites_are_transparent_and_the_chopper_is_drawn_on_top() {
    let chopper = Rect::placed(100, 200, CHOPPER_SIZE);
    let bird = Rect::placed(100, 200, BIRD_SIZE);
    let tank = Rect::placed(400, 300, FUEL_TANK_SIZE);
    let alone = World { chopper, fuel_tanks: vec![tank], ..World::default() };
    let both = World { birds: vec![bird], ..alone.clone() };
    let mut r = Renderer::new(600, 800, Hud::Off);
    let (mut a, mut b) = (vec![0; r.frame_len()], vec![0; r.frame_len()]);
    r.draw_full(&alone, HudScale::default(), &mut a);
    r.draw_full(&both, HudScale::default(), &mut b);
    // The chopper box has background pixels (transparency) and coloured ones.
    let in_box = |f: &[u8], x0: usize, y0: usize, s: usize| -> Vec<[u8; 3]> {
        (y0..y0 + s).flat_map(|y| (x0..x0 + s).map(move |x| (x, y))).map(|(x, y)| px(f, x, y)).collect()
    };
    let chopper_px = in_box(&a, 100, 200, 64);
    assert!(chopper_px.contains(&[255; 3]) && chopper_px.iter().any(|p| *p != [255; 3]));
    // Wherever the chopper is opaque it hides the bird under it; elsewhere the bird shows.
    let (with_bird, without) = (in_box(&b, 100, 200, 64), chopper_px);
    for (p, q) in with_bird.iter().zip(&without) {
        if *q != [255; 3] {
            assert_eq!(p, q);
        }
    }
    assert_ne!(with_bird, without, "the bird shows through the chopper's transparent pixels");
    // Outside any box, white.
    assert_eq!(px(&a, 700, 500), [255; 3]);
    assert!(in_box(&a, 400, 300, 32).iter().any(|p| *p != [255; 3]), "the tank is drawn");
}

#[test]
fn small_frames_scale_geometry_instead_of_losing_sprites() {
    let world = World { chopper: Rect::placed(400, 300, CHOPPER_SIZE), ..World::default() };
    let mut r = Renderer::with_format(84, 84, Hud::Off, PixelFormat::Gray);
    let mut f = vec![0; r.frame_len()];
    r.draw_full(&world, HudScale::default(), &mut f);
    let dark: Vec<usize> = (0..f.len()).filter(|&i| f[i] < 255).collect();
    assert!(!dark.is_empty());
    // The chopper at (400, 300) of 800 × 600 lands at (42, 42) of 84 × 84, about 7 × 9 pixels.
    for &i in &dark {
        let (x, y) = (i % 84, i / 84);
        assert!((42..49).contains(&x) && (42..51).contains(&y), "pixel ({x}, {y}) outside the scaled box");
    }
}

#[test]
fn the_same_seed_and_actions_give_identical_frames() {
    let (_, a) = run(&[("obs_size", "97x131")], 300);
    let (_, b) = run(&[("obs_size", "97x131")], 300);
    assert!(a == b);
}
