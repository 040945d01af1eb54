//! What the page drives, in plain Rust: one environment, its frame buffers and the heuristic pilot.
//!
//! Nothing here touches JavaScript, so it is tested natively; `lib.rs` only maps it to `wasm-bindgen`.

use chopperscape::policy::{self, Policy};
use chopperscape::{Action, ChopperScape, Config, ObsBufMut, ObsType, Status, Transition, World, features};

/// Height of the frame the page shows, in pixels.
pub const FRAME_HEIGHT: usize = chopperscape::consts::HEIGHT as usize;
/// Width of the frame the page shows, in pixels.
pub const FRAME_WIDTH: usize = chopperscape::consts::WIDTH as usize;

/// Options the page may set: the SPEC options that change play. Observation settings are the page's own
/// business (it always shows the full frame), so they are refused.
pub const PAGE_OPTIONS: &[&str] =
    &["lives", "alien_prob", "bird_prob", "fuel_prob", "max_fuel", "bird_fuel_collision", "sticky_prob", "frame_skip"];

/// One game as the page plays it.
pub struct Session {
    env: ChopperScape,
    pilot: Box<dyn Policy + Send>,
    /// The features observation `step_into` writes: the cheapest observation, unused by the page.
    features: Vec<f32>,
    rgb: Vec<u8>,
    rgba: Vec<u8>,
}

impl Session {
    /// A session with these `(name, value)` options, parsed as `Config::set` parses them.
    ///
    /// # Errors
    /// An option the page does not offer, or a value out of range; the message names the option and what
    /// is allowed.
    pub fn new<'a>(options: impl IntoIterator<Item = (&'a str, &'a str)>) -> Result<Session, String> {
        let mut config = Config { obs_type: ObsType::Features, ..Config::default() };
        for (name, value) in options {
            if !PAGE_OPTIONS.contains(&name) {
                return Err(format!("unknown option `{name}`: allowed options are {}", PAGE_OPTIONS.join(", ")));
            }
            config.set(name, value).map_err(|e| e.to_string())?;
        }
        let env = ChopperScape::new(config).map_err(|e| e.to_string())?;
        let pilot = heuristic(env.config());
        let mut rgba = vec![0; FRAME_HEIGHT * FRAME_WIDTH * 4];
        // Alpha never changes: the frame is opaque.
        rgba.chunks_exact_mut(4).for_each(|px| px[3] = 255);
        Ok(Session {
            env,
            pilot,
            features: vec![0.0; features::FEATURES_LEN],
            rgb: vec![0; FRAME_HEIGHT * FRAME_WIDTH * 3],
            rgba,
        })
    }

    /// Starts an episode from `seed` and draws its first frame.
    pub fn reset(&mut self, seed: u64) {
        self.env.reset_into(Some(seed), ObsBufMut::F32(&mut self.features)).expect("the features buffer fits");
        self.pilot = heuristic(self.env.config());
        self.draw();
    }

    /// Advances one step with `action` (0 Right, 1 Left, 2 Down, 3 Up, 4 Do Nothing) and draws the frame.
    ///
    /// # Errors
    /// An invalid action, a step before `reset` or after the episode ended; nothing changes then.
    pub fn step(&mut self, action: i64) -> Result<Transition, String> {
        let t = self.env.step_into(action, ObsBufMut::F32(&mut self.features)).map_err(|e| e.to_string())?;
        self.draw();
        Ok(t)
    }

    /// The action the heuristic pilot picks for the current state.
    pub fn pilot_action(&mut self) -> Action {
        self.pilot.act(self.env.world())
    }

    /// The current state.
    pub fn world(&self) -> &World {
        self.env.world()
    }

    /// Whether the episode has ended (or not started).
    pub fn is_over(&self) -> bool {
        !matches!(self.env.world().status, Status::Running)
    }

    /// The last frame, RGB, 600 × 800 × 3, row-major.
    pub fn rgb(&self) -> &[u8] {
        &self.rgb
    }

    /// The last frame, RGBA with opaque alpha, 600 × 800 × 4: what a canvas `ImageData` holds.
    pub fn rgba(&self) -> &[u8] {
        &self.rgba
    }

    fn draw(&mut self) {
        self.env.render_into(&mut self.rgb).expect("the frame buffer is 600 × 800 × 3");
        for (px, rgb) in self.rgba.chunks_exact_mut(4).zip(self.rgb.chunks_exact(3)) {
            px[..3].copy_from_slice(rgb);
        }
    }
}

fn heuristic(config: &Config) -> Box<dyn Policy + Send> {
    policy::by_name("heuristic", 0, config).expect("the heuristic pilot is built in")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn session(options: &[(&str, &str)]) -> Session {
        Session::new(options.iter().copied()).unwrap()
    }

    #[test]
    fn frames_match_the_native_renderer_for_the_same_seed_and_actions() {
        let mut s = session(&[("lives", "3"), ("alien_prob", "0.05")]);
        let mut env = ChopperScape::new(Config { lives: 3, alien_prob: 0.05, ..Config::default() }).unwrap();
        s.reset(11);
        chopperscape::Env::reset(&mut env, Some(11));
        for i in 0..120 {
            if s.is_over() {
                break;
            }
            let a = i % 5;
            let t = s.step(a).unwrap();
            let native = chopperscape::Env::step(&mut env, a).unwrap();
            assert_eq!((t.reward, t.terminated, t.info), (native.reward, native.terminated, native.info));
            assert_eq!(s.rgb(), env.render().as_slice(), "frame after step {i}");
        }
    }

    #[test]
    fn rgba_frame_is_the_rgb_frame_with_opaque_alpha() {
        let mut s = session(&[]);
        s.reset(3);
        s.step(3).unwrap();
        assert_eq!(s.rgba().len(), FRAME_HEIGHT * FRAME_WIDTH * 4);
        for (px, rgb) in s.rgba().chunks_exact(4).zip(s.rgb().chunks_exact(3)) {
            assert_eq!(&px[..3], rgb);
            assert_eq!(px[3], 255);
        }
        assert!(s.rgb().iter().any(|&b| b != 255), "the frame shows something besides the white sky");
    }

    #[test]
    fn options_are_applied() {
        let mut s = session(&[("lives", "4"), ("max_fuel", "50")]);
        s.reset(0);
        assert_eq!(s.world().lives, 4);
        assert_eq!(s.world().fuel_left, 50);
    }

    #[test]
    fn bad_options_are_refused_with_the_option_named() {
        let err = Session::new([("lives", "0")]).err().unwrap();
        assert!(err.contains("lives") && err.contains("1..=1000"), "{err}");
        let err = Session::new([("alien_prob", "2")]).err().unwrap();
        assert!(err.contains("alien_prob"), "{err}");
        let err = Session::new([("obs_type", "features")]).err().unwrap();
        assert!(err.contains("obs_type") && err.contains("lives"), "{err}");
    }

    #[test]
    fn invalid_action_is_refused_and_changes_nothing() {
        let mut s = session(&[]);
        s.reset(5);
        let before = s.world().clone();
        let err = s.step(7).unwrap_err();
        assert!(err.contains('7') && err.contains("0..=4"), "{err}");
        assert_eq!(s.world(), &before);
    }

    #[test]
    fn stepping_after_the_episode_ended_is_refused() {
        let mut s = session(&[("max_fuel", "3")]);
        s.reset(1);
        for _ in 0..3 {
            s.step(4).unwrap();
        }
        assert!(s.is_over());
        assert!(s.step(4).unwrap_err().contains("reset"));
    }

    #[test]
    fn pilot_flies_the_same_way_from_the_same_seed() {
        let run = || {
            let mut s = session(&[]);
            s.reset(9);
            let mut path = Vec::new();
            while !s.is_over() && path.len() < 60 {
                let a = s.pilot_action();
                s.step(a as i64).unwrap();
                path.push((s.world().chopper.x, s.world().chopper.y));
            }
            path
        };
        let (a, b) = (run(), run());
        assert_eq!(a, b);
        assert!(a.windows(2).any(|w| w[0] != w[1]), "the pilot moves the chopper");
    }
}
