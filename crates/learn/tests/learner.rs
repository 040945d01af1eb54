//! A short run end to end: the curve's rows, a resumed run that goes on exactly, and the export that
//! `chopperscape-policy` loads and plays as the learner's own greedy policy.

use chopperscape::{Config, Env, ObsData};
use chopperscape_learn::export::{ExportInfo, python_json, to_onnx};
use chopperscape_learn::{Learner, Recipe, State};
use chopperscape_policy::Policy;

fn small() -> Recipe {
    Recipe { num_envs: 8, num_steps: 32, total_steps: 2_000, ..Recipe::fast() }
}

#[test]
fn a_resumed_run_goes_on_exactly() {
    let mut whole = Learner::new(small()).unwrap();
    let rows: Vec<_> = (0..3).map(|_| whole.update(0.0).unwrap()).collect();
    assert_eq!(rows[2].env_steps, whole.env_steps());
    assert!(rows.iter().all(|r| r.entropy > 1.0 && r.entropy <= 5f64.ln() + 1e-6));
    let mut first = Learner::new(small()).unwrap();
    first.update(0.0).unwrap();
    let text = serde_json::to_string(&first.state().unwrap()).unwrap();
    drop(first);
    let state: State = serde_json::from_str(&text).unwrap();
    let mut resumed = Learner::from_state(state).unwrap();
    let again: Vec<_> = (0..2).map(|_| resumed.update(0.0).unwrap()).collect();
    assert_eq!(again, rows[1..]);
}

#[test]
fn the_export_plays_as_the_learner() {
    let mut learner = Learner::new(small()).unwrap();
    learner.update(0.0).unwrap();
    let info = ExportInfo { env_options: python_json(&small().env_options), train_seeds: vec![(0, 8)] };
    assert_eq!(info.env_options, r#"{"frame_skip": 4}"#);
    let bytes = to_onnx(learner.agent(), learner.obs_norm(), &info).unwrap();
    let mut policy = Policy::from_bytes(&bytes).unwrap();
    let mut config = Config::features();
    config.set("frame_skip", "4").unwrap();
    let mut env = chopperscape::ChopperScape::new(config).unwrap();
    let mut obs = env.reset(Some(3)).0;
    for _ in 0..50 {
        let ObsData::F32(raw) = obs.data.clone() else { panic!("features") };
        let theirs = policy.act(&obs).unwrap();
        assert_eq!(theirs as usize, learner.greedy(&raw).unwrap());
        let step = env.step(theirs as i64).unwrap();
        obs = step.observation;
        if step.terminated || step.truncated {
            break;
        }
    }
}

/// Laps that count each phase's calls.
#[derive(Default)]
struct Count([u64; 9]);

impl chopperscape_learn::phases::Laps for Count {
    fn lap(&mut self, phase: chopperscape_learn::phases::Phase) {
        self.0[phase as usize] += 1;
    }
}

#[test]
fn timed_updates_are_the_same_updates_and_lap_every_phase_but_logging() {
    let (mut plain, mut timed) = (Learner::new(small()).unwrap(), Learner::new(small()).unwrap());
    let mut count = Count::default();
    for _ in 0..2 {
        assert_eq!(plain.update(0.0).unwrap(), timed.update_laps(0.0, &mut count).unwrap());
    }
    let (steps, minibatches) = (2 * 32, 2 * small().update_epochs * small().num_minibatches);
    let names = chopperscape_learn::phases::PHASES;
    let seen: std::collections::HashMap<_, _> = names.iter().zip(count.0).collect();
    assert_eq!(seen[&"env"], steps as u64);
    assert_eq!(seen[&"obs_norm"], steps as u64);
    assert_eq!(seen[&"forward"], steps as u64);
    assert_eq!(seen[&"gae"], 2);
    for phase in ["update_forward", "backward", "optimizer"] {
        assert_eq!(seen[&phase], minibatches as u64, "{phase}");
    }
    assert_eq!(seen[&"logging"], 0, "logging is the caller's");
    // The phases are Python's (python/chopperscape/learn/phases.py), in its order.
    let python =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../python/chopperscape/learn/phases.py"))
            .unwrap();
    let line = python.lines().find(|l| l.starts_with("PHASES = (")).expect("Python's PHASES");
    let quoted: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
    assert_eq!(line, format!("PHASES = ({})", quoted.join(", ")));
}

#[test]
fn the_evaluation_plays_the_exports_episodes_and_the_heuristic_the_same_seeds() {
    use chopperscape_learn::evaluate::{heuristic, mean};
    let mut learner = Learner::new(small()).unwrap();
    learner.update(0.0).unwrap();
    let ours = learner.evaluate(3, 1_000_000).unwrap();
    assert_eq!(ours.iter().map(|e| e.seed).collect::<Vec<_>>(), [1_000_000, 1_000_001, 1_000_002]);
    // The same episodes through the exported policy, played by hand.
    let info = ExportInfo { env_options: python_json(&small().env_options), train_seeds: vec![(0, 8)] };
    let mut policy = Policy::from_bytes(&to_onnx(learner.agent(), learner.obs_norm(), &info).unwrap()).unwrap();
    let mut config = Config::features();
    config.set("frame_skip", "4").unwrap();
    for e in &ours {
        let mut env = chopperscape::ChopperScape::new(config.clone()).unwrap();
        let mut obs = env.reset(Some(e.seed)).0;
        let (mut ret, mut steps) = (0.0, 0);
        loop {
            let step = env.step(policy.act(&obs).unwrap() as i64).unwrap();
            (ret, steps) = (ret + f64::from(step.reward), steps + 1);
            if step.terminated || step.truncated {
                break;
            }
            obs = step.observation;
        }
        assert_eq!((e.ret, e.steps), (ret, steps), "seed {}", e.seed);
    }
    let h = heuristic(&config, 3, 1_000_000).unwrap();
    assert!(h.iter().all(|e| e.steps > 0) && mean(&h) > mean(&ours), "{h:?} vs {ours:?}");
    assert_eq!(h, heuristic(&config, 3, 1_000_000).unwrap(), "deterministic");
}
