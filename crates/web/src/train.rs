//! "Train" in the page: the Rust learner (`chopperscape-learn`, the `fast` recipe) as a JavaScript class, run in a
//! Web Worker (`web/train-worker.js`) so that learning never blocks the page. Each [`Trainer::update`] is one PPO
//! update and gives its row of the learning curve; [`Trainer::onnx`] is the current policy in the export's
//! format, which the page flies (`Game.with_policy`) and offers for download.

use chopperscape_learn::evaluate::{heuristic, mean};
use chopperscape_learn::export::{ExportInfo, python_json, to_onnx};
use chopperscape_learn::progress::header;
use chopperscape_learn::{Learner, Recipe, env_config};
use wasm_bindgen::prelude::*;

/// A PPO run of the `fast` recipe in memory.
#[wasm_bindgen]
pub struct Trainer {
    learner: Learner,
}

fn js(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
}

#[wasm_bindgen]
impl Trainer {
    /// The `fast` preset with training seed `seed`, `num_envs` envs of `num_steps` steps an update (0: the
    /// preset's 128 × 128) and a budget of `total_steps` decisions (0: the preset's 3 M).
    #[wasm_bindgen(constructor)]
    pub fn new(seed: u32, num_envs: u32, num_steps: u32, total_steps: f64) -> Result<Trainer, JsError> {
        let mut recipe = Recipe { seed: u64::from(seed), ..Recipe::fast() };
        if num_envs > 0 {
            recipe.num_envs = num_envs as usize;
        }
        if num_steps > 0 {
            recipe.num_steps = num_steps as usize;
        }
        if total_steps >= 1.0 {
            recipe.total_steps = total_steps as u64;
        }
        Ok(Trainer { learner: Learner::new(recipe).map_err(js)? })
    }

    /// One update; its row of `progress.csv` (the columns of [`Trainer::csv_header`]), `wall_s` the run's seconds.
    pub fn update(&mut self, wall_s: f64) -> Result<String, JsError> {
        let mut row = self.learner.update(wall_s).map_err(js)?;
        row.wall_s = wall_s;
        Ok(row.csv_line())
    }

    /// The header of the learning-curve CSV (Python's columns).
    pub fn csv_header() -> String {
        header()
    }

    /// The current policy's mean return, greedy, on `episodes` episodes from seed `first_seed` under the recipe's
    /// rules: the held-out evaluation the page draws beside the training curve.
    pub fn evaluate(&self, episodes: u32, first_seed: f64) -> Result<f64, JsError> {
        Ok(mean(&self.learner.evaluate(u64::from(episodes), first_seed as u64).map_err(js)?))
    }

    /// The heuristic policy's mean return on the same episodes, under this run's rules.
    pub fn heuristic(&self, episodes: u32, first_seed: f64) -> Result<f64, JsError> {
        let config = env_config(self.learner.recipe()).map_err(js)?;
        Ok(mean(&heuristic(&config, u64::from(episodes), first_seed as u64).map_err(js)?))
    }

    /// Decisions learned from so far.
    pub fn env_steps(&self) -> f64 {
        self.learner.env_steps() as f64
    }

    /// Whether the step budget is spent.
    pub fn finished(&self) -> bool {
        self.learner.finished()
    }

    /// The current policy as an ONNX file (`chopperscape-policy/1`, as `chopperscape train` writes it).
    pub fn onnx(&self) -> Result<Vec<u8>, JsError> {
        let recipe = self.learner.recipe();
        let info = ExportInfo {
            env_options: python_json(&recipe.env_options),
            train_seeds: vec![(recipe.seed, recipe.num_envs as u64)],
        };
        to_onnx(self.learner.agent(), self.learner.obs_norm(), &info).map_err(js)
    }
}
