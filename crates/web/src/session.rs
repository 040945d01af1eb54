//! What the page drives, in plain Rust: one environment, its frame buffers, the heuristic policy and, when the
//! page loaded one, a trained policy (`chopperscape-policy`, the same code as `chopperscape demo --policy`).
//!
//! Nothing here touches JavaScript, so it is tested natively; `lib.rs` only maps it to `wasm-bindgen`.

use chopperscape::policy::{self, Policy};
use chopperscape::{
    Action, ChopperScape, Config, ConfigError, Env, OPTIONS, ObsType, Observation, Status, Transition, World,
};

/// Height of the frame the page shows, in pixels.
pub const FRAME_HEIGHT: usize = chopperscape::consts::HEIGHT as usize;
/// Width of the frame the page shows, in pixels.
pub const FRAME_WIDTH: usize = chopperscape::consts::WIDTH as usize;

/// Options the page may set: those the core's table marks `page` ([`chopperscape::OptionInfo::page`]), the SPEC
/// options that change play, in table order. Observation settings are the page's own business (it always shows the
/// full frame), so they are refused.
pub const PAGE_OPTIONS: &[&str] = &page_options::<{ page_count() }>();

/// Every name the page takes: `mode`, then [`PAGE_OPTIONS`] (what the error for another name lists).
const PAGE_NAMES: &[&str] = &page_names::<{ page_count() + 1 }>();

/// `mode` and the page's options, in that order.
const fn page_names<const N: usize>() -> [&'static str; N] {
    let mut names = ["mode"; N];
    let mut i = 0;
    while i < PAGE_OPTIONS.len() {
        names[i + 1] = PAGE_OPTIONS[i];
        i += 1;
    }
    names
}

/// How many options of the core's table the page sets.
const fn page_count() -> usize {
    let (mut n, mut i) = (0, 0);
    while i < OPTIONS.len() {
        n += OPTIONS[i].page as usize;
        i += 1;
    }
    n
}

/// The names of the options of the core's table the page sets, in table order.
const fn page_options<const N: usize>() -> [&'static str; N] {
    let mut names = [""; N];
    let (mut n, mut i) = (0, 0);
    while i < OPTIONS.len() {
        if OPTIONS[i].page {
            names[n] = OPTIONS[i].name;
            n += 1;
        }
        i += 1;
    }
    names
}

/// One game as the page plays it.
pub struct Session {
    env: ChopperScape,
    /// The built-in heuristic policy, which flies when the page is asked to watch.
    heuristic: Box<dyn Policy + Send>,
    /// The trained policy, if the page loaded one.
    agent: Option<chopperscape_policy::Policy>,
    /// The observation `step_into` writes: features, the cheapest, which a trained policy reads.
    obs: Observation,
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
        Session::build(Config { obs_type: ObsType::Features, ..Config::default() }, options, None)
    }

    /// A session flown by the trained policy in `policy` (the bytes of an exported `.onnx`), under the options
    /// it was trained with (its observation too: a pixel policy sees its small frames while the page shows the
    /// full one), then these page options.
    ///
    /// # Errors
    /// A file that is not a policy, or a bad option.
    pub fn with_policy<'a>(
        policy: &[u8],
        options: impl IntoIterator<Item = (&'a str, &'a str)>,
    ) -> Result<Session, String> {
        let agent = chopperscape_policy::Policy::from_bytes(policy).map_err(|e| e.to_string())?;
        let config = agent.config().map_err(|e| e.to_string())?;
        Session::build(config, options, Some(agent))
    }

    fn build<'a>(
        config: Config,
        options: impl IntoIterator<Item = (&'a str, &'a str)>,
        agent: Option<chopperscape_policy::Policy>,
    ) -> Result<Session, String> {
        // `mode` (a name of chopperscape::MODES, as `--mode` and Python's `mode=` take it) is applied first,
        // wherever it stands; the other options go on top and may not contradict it (the core's `configure`).
        let options: Vec<(&str, &str)> = options.into_iter().collect();
        let mut mode = None;
        for &(name, value) in &options {
            if name == "mode" && !value.is_empty() {
                mode = Some(chopperscape::mode(value).ok_or_else(|| {
                    format!("invalid value {value:?} for `mode`: allowed {}", chopperscape::mode_names())
                })?);
            }
        }
        let set = |config: &mut Config| {
            for &(name, value) in options.iter().filter(|(name, _)| *name != "mode") {
                if !PAGE_OPTIONS.contains(&name) {
                    return Err(ConfigError::Unknown { name: name.to_string(), allowed: PAGE_NAMES });
                }
                config.set(name, value)?;
            }
            Ok(())
        };
        let config = chopperscape::configure(config, mode, set).map_err(|e| e.to_string())?;
        if let Some(agent) = &agent {
            agent.check(&config).map_err(|e| e.to_string())?;
        }
        let env = ChopperScape::new(config).map_err(|e| e.to_string())?;
        let heuristic = heuristic(env.config());
        let space = env.observation_space();
        let obs = Observation::zeros(space.shape.clone(), space.dtype);
        let mut rgba = vec![0; FRAME_HEIGHT * FRAME_WIDTH * 4];
        // Alpha never changes: the frame is opaque.
        rgba.chunks_exact_mut(4).for_each(|px| px[3] = 255);
        Ok(Session { env, heuristic, agent, obs, rgb: vec![0; FRAME_HEIGHT * FRAME_WIDTH * 3], rgba })
    }

    /// Starts an episode from `seed` and draws its first frame.
    pub fn reset(&mut self, seed: u64) {
        self.env.reset_into(Some(seed), self.obs.as_buf_mut()).expect("the observation buffer fits");
        self.heuristic = heuristic(self.env.config());
        self.draw();
    }

    /// Advances one step with `action` (0 Right, 1 Left, 2 Down, 3 Up, 4 Do Nothing) and draws the frame.
    ///
    /// # Errors
    /// An invalid action, a step before `reset` or after the episode ended; nothing changes then.
    pub fn step(&mut self, action: i64) -> Result<Transition, String> {
        let t = self.env.step_into(action, self.obs.as_buf_mut()).map_err(|e| e.to_string())?;
        self.draw();
        Ok(t)
    }

    /// The action the heuristic policy picks for the current state.
    pub fn heuristic_action(&mut self) -> Action {
        self.heuristic.act(self.env.world())
    }

    /// The action the trained policy picks for the current observation (greedy), if a policy flies.
    ///
    /// # Errors
    /// No policy was loaded, or it failed.
    pub fn agent_action(&mut self) -> Result<Action, String> {
        let agent = self.agent.as_mut().ok_or("no trained policy was loaded")?;
        agent.act(&self.obs).map_err(|e| e.to_string())
    }

    /// Whether a trained policy was loaded.
    pub fn has_agent(&self) -> bool {
        self.agent.is_some()
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
    policy::by_name("heuristic", 0, config).expect("the heuristic policy is built in")
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

    /// Walks the core's table: the page takes each option marked `page` (its default and a value the option
    /// allows) and refuses every other option by name, listing exactly the page's options.
    #[test]
    fn the_page_takes_exactly_the_page_options_of_the_table() {
        for o in OPTIONS {
            let result = Session::new([(o.name, o.default)]);
            if o.page {
                assert!(result.is_ok(), "{}: {:?}", o.name, result.err());
                assert!(PAGE_OPTIONS.contains(&o.name));
            } else {
                let err = result.err().unwrap_or_else(|| panic!("the page took {}", o.name));
                let listed = err.split("allowed options are mode, ").nth(1).unwrap_or_default();
                assert!(err.contains(&format!("`{}`", o.name)), "{err}");
                assert_eq!(listed.split(", ").collect::<Vec<_>>(), PAGE_OPTIONS, "{err}");
                assert!(!PAGE_OPTIONS.contains(&o.name));
            }
        }
        let page: Vec<&str> = OPTIONS.iter().filter(|o| o.page).map(|o| o.name).collect();
        assert_eq!(PAGE_OPTIONS, page);
        assert!(PAGE_OPTIONS.iter().all(|name| chopperscape::option_info(name).is_some_and(|o| o.rule)));
    }

    /// The page's `mode` is the core's: each mode plays the game of its options given one by one (the same rewards,
    /// ends and frames); an unknown name, or a page option that contradicts the mode, is refused naming it.
    #[test]
    fn a_mode_is_its_options_and_refuses_contradictions() {
        for m in chopperscape::MODES {
            let mut by_mode = session(&[("mode", m.name)]);
            let mut by_hand = session(m.options);
            assert_eq!(by_mode.env.config(), &Config { obs_type: ObsType::Features, ..m.config().unwrap() });
            by_mode.reset(4);
            by_hand.reset(4);
            for i in 0..200_i64 {
                if by_mode.is_over() {
                    break;
                }
                assert_eq!(by_mode.step(i % 5).unwrap(), by_hand.step(i % 5).unwrap(), "{} step {i}", m.name);
                assert_eq!(by_mode.rgb(), by_hand.rgb(), "{} step {i}", m.name);
            }
        }
        let err = Session::new([("mode", "hard-v9")]).err().unwrap();
        assert!(err.contains("hard-v9") && err.contains("sticky-v0"), "{err}");
        let err = Session::new([("lives", "7"), ("mode", "full-v0")]).err().unwrap();
        assert!(err.contains("contradict mode \"full-v0\"") && err.contains("lives 7 != 3"), "{err}");
        assert!(Session::new([("mode", "v0"), ("lives", "1")]).is_ok());
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

    const POLICY: &[u8] = include_bytes!("../../../models/ppo-features.onnx");

    #[test]
    fn the_trained_agent_plays_the_command_lines_episode() {
        // The episode of `chopperscape demo --policy models/ppo-features.onnx --seed 3 --aliens 0.05`.
        let mut s = Session::with_policy(POLICY, [("alien_prob", "0.05")]).unwrap();
        s.reset(3);
        let config = Config { alien_prob: 0.05, ..Config::features() };
        let mut policy = chopperscape_policy::Policy::from_bytes(POLICY).unwrap();
        let mut env = ChopperScape::new(config).unwrap();
        let (mut obs, _) = env.reset(Some(3));
        while !s.is_over() {
            let a = s.agent_action().unwrap();
            assert_eq!(a, policy.act(&obs).unwrap());
            s.step(a as i64).unwrap();
            obs = env.step(a as i64).unwrap().observation;
        }
        assert_eq!(s.world(), env.world());
        assert!(s.world().steps > 10);
    }

    #[test]
    fn the_pixel_agent_flies_on_its_own_frames_while_the_page_shows_the_full_one() {
        // `models/ppo-pixels.onnx` learned pixel layout 3 (the agent view) at 42 × 42 × 4, frame skip 4: the session's
        // env draws those frames for the policy and the 600 × 800 frame (the art) for the page.
        const PIXELS: &[u8] = include_bytes!("../../../models/ppo-pixels.onnx");
        let mut s = Session::with_policy(PIXELS, [("alien_prob", "0.05")]).unwrap();
        s.reset(3);
        let mut policy = chopperscape_policy::Policy::from_bytes(PIXELS).unwrap();
        let config = policy.config().unwrap();
        assert_eq!((config.obs_type, config.look), (ObsType::Grayscale, chopperscape::Look::Auto));
        assert_eq!(config.obs_size, (42, 42));
        let mut env = ChopperScape::new(Config { alien_prob: 0.05, ..config }).unwrap();
        let (mut obs, _) = env.reset(Some(3));
        for _ in 0..40 {
            if s.is_over() {
                break;
            }
            let a = s.agent_action().unwrap();
            assert_eq!(a, policy.act(&obs).unwrap());
            s.step(a as i64).unwrap();
            obs = env.step(a as i64).unwrap().observation;
        }
        assert_eq!(s.world(), env.world());
        assert_eq!(s.rgb(), env.render().as_slice());
    }

    #[test]
    fn a_bad_policy_file_is_refused_with_a_message() {
        let err = Session::with_policy(&POLICY[..200], []).err().unwrap();
        assert!(err.contains("not a ChopperScape policy"), "{err}");
        let err = Session::with_policy(POLICY, [("lives", "0")]).err().unwrap();
        assert!(err.contains("lives"), "{err}");
        assert!(session(&[]).agent_action().unwrap_err().contains("no trained policy"));
    }

    #[test]
    fn a_hostile_policy_file_meets_the_loaders_limits() {
        // The page loads policies through `Policy::from_bytes`, so the same checks run before tract (where a
        // panic aborts the WebAssembly instance). The committed policy's graph with its first node's `Gemm`
        // swapped for a `Conv` padded by 2^63 − 1 (the file of issue 32 that hung `demo`), and a chain of
        // 4,000 nodes.
        use prost::Message;
        use tract_onnx::pb::{AttributeProto, ModelProto, NodeProto};
        let mut m = ModelProto::decode(POLICY).unwrap();
        let g = m.graph.as_mut().unwrap();
        let gemm = g.node.iter_mut().find(|n| n.op_type == "Gemm").unwrap();
        gemm.op_type = "Conv".into();
        gemm.attribute =
            vec![AttributeProto { name: "pads".into(), r#type: 7, ints: vec![i64::MAX; 2], ..Default::default() }];
        let err = Session::with_policy(&m.encode_to_vec(), []).err().unwrap();
        assert!(err.contains("has pads = [9223372036854775807, 9223372036854775807]"), "{err}");
        let g = m.graph.as_mut().unwrap();
        g.node = (0..4000)
            .map(|i| NodeProto {
                op_type: "Relu".into(),
                input: vec![if i == 0 { "obs".into() } else { format!("r{}", i - 1) }],
                output: vec![if i == 3999 { "logits".into() } else { format!("r{i}") }],
                ..Default::default()
            })
            .collect();
        let start = std::time::Instant::now();
        let err = Session::with_policy(&m.encode_to_vec(), []).err().unwrap();
        assert!(err.contains("the graph has 4000 nodes") && start.elapsed().as_secs() < 2, "{err}");
    }

    #[test]
    fn heuristic_flies_the_same_way_from_the_same_seed() {
        let run = || {
            let mut s = session(&[]);
            s.reset(9);
            let mut path = Vec::new();
            while !s.is_over() && path.len() < 60 {
                let a = s.heuristic_action();
                s.step(a as i64).unwrap();
                path.push((s.world().chopper.x, s.world().chopper.y));
            }
            path
        };
        let (a, b) = (run(), run());
        assert_eq!(a, b);
        assert!(a.windows(2).any(|w| w[0] != w[1]), "the heuristic moves the chopper");
    }
}
