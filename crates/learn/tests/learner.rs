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
