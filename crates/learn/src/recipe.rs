//! The recipe's settings: [`Recipe`], the same fields and defaults as Python's `chopperscape.learn.recipe.Recipe`
//! (so that `recipe.json` reads the same), and the presets this learner trains (`features`, `fast`).
//!
//! `tests/recipe.rs` checks both presets equal to Python's `PRESETS` (a golden JSON written by
//! `tests/golden/make_golden.py`).

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

/// The learning rate's floor (`LR_FLOOR` in Python): the rate decays linearly over the step budget to 5 % of
/// itself, reached at 0.95 of the budget.
pub const LR_FLOOR: f64 = 0.05;

/// The presets this learner trains: the features recipe and `fast` (the MLP presets; the pixel presets need a CNN).
pub const PRESETS: &[&str] = &["fast", "features"];

/// The largest step budget (`MAX_TOTAL_STEPS` in Python).
pub const MAX_TOTAL_STEPS: u64 = 1_000_000_000_000;

/// The widest MLP (`MAX_HIDDEN` in Python).
pub const MAX_HIDDEN: usize = 4096;

/// Hyperparameters of PPO, as Python's `Recipe` (field for field, in its order). The pixel-only settings
/// (`aux_coef`, `invert_frames`, `teacher*`, `augment`) are carried so the run's `recipe.json` is Python's; this
/// learner trains only what their defaults mean.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[allow(missing_docs)] // the fields are Python's, documented there (`learn/recipe.py`)
pub struct Recipe {
    pub obs_type: String,
    pub env_options: Map<String, Value>,
    pub num_envs: usize,
    pub num_steps: usize,
    pub gamma: f64,
    pub gae_lambda: f64,
    pub learning_rate: f64,
    pub anneal_lr: bool,
    pub update_epochs: usize,
    pub num_minibatches: usize,
    pub clip_coef: f64,
    pub ent_coef: f64,
    pub vf_coef: f64,
    pub max_grad_norm: f64,
    pub hidden: usize,
    pub network: String,
    pub device: String,
    pub norm_obs: bool,
    pub norm_reward: bool,
    pub seed: u64,
    pub torch_threads: usize,
    pub env_threads: usize,
    pub total_steps: u64,
    pub aux_coef: f64,
    pub invert_frames: bool,
    pub teacher: String,
    pub teacher_coef: f64,
    pub teacher_fade: f64,
    pub augment: String,
}

impl Default for Recipe {
    /// Python's `Recipe()`: the features recipe.
    fn default() -> Recipe {
        Recipe {
            obs_type: "features".into(),
            env_options: Map::new(),
            num_envs: 64,
            num_steps: 256,
            gamma: 0.9995,
            gae_lambda: 0.95,
            learning_rate: 3e-4,
            anneal_lr: true,
            update_epochs: 4,
            num_minibatches: 8,
            clip_coef: 0.2,
            ent_coef: 0.02,
            vf_coef: 0.5,
            max_grad_norm: 0.5,
            hidden: 128,
            network: "auto".into(),
            device: "cpu".into(),
            norm_obs: true,
            norm_reward: true,
            seed: 0,
            torch_threads: 1,
            env_threads: 1,
            total_steps: 15_000_000,
            aux_coef: 0.0,
            invert_frames: true,
            teacher: String::new(),
            teacher_coef: 1.0,
            teacher_fade: 1.0,
            augment: "none".into(),
        }
    }
}

impl Recipe {
    /// The preset `name` (`fast` or `features`, Python's `PRESETS[name]` over the defaults); `None` for another.
    pub fn preset(name: &str) -> Option<Recipe> {
        match name {
            "features" => Some(Recipe::default()),
            "fast" => Some(Recipe::fast()),
            _ => None,
        }
    }

    /// The `fast` preset: frame skip 4, γ 0.998, λ 0.98, 128 envs × 128 steps, 2 epochs of 4 minibatches at a
    /// learning rate of 1e-3, 3 M decisions.
    pub fn fast() -> Recipe {
        let mut env_options = Map::new();
        env_options.insert("frame_skip".into(), Value::from(4));
        Recipe {
            env_options,
            gamma: 0.998,
            gae_lambda: 0.98,
            num_envs: 128,
            num_steps: 128,
            num_minibatches: 4,
            update_epochs: 2,
            learning_rate: 1e-3,
            total_steps: 3_000_000,
            ..Recipe::default()
        }
    }

    /// The learning rate after `env_steps` of the budget (Python's schedule: linear, floored at [`LR_FLOOR`]).
    pub fn learning_rate_at(&self, env_steps: u64) -> f64 {
        if !self.anneal_lr {
            return self.learning_rate;
        }
        self.learning_rate * (1.0 - env_steps as f64 / self.total_steps as f64).max(LR_FLOOR)
    }

    /// The first setting out of range, as Python's `check_recipe` words it; and what this learner cannot train
    /// (observations other than features, a CNN, the pixel recipes' guidance).
    ///
    /// # Errors
    /// A message naming the setting.
    pub fn check(&self) -> Result<(), String> {
        let int = |name: &str, v: u64, max: u64| {
            if v == 0 || v > max {
                Err(format!("invalid value {v} for option `{name}`: allowed 1..={max}"))
            } else {
                Ok(())
            }
        };
        int("num_envs", self.num_envs as u64, 1 << 20)?;
        int("num_steps", self.num_steps as u64, 1 << 20)?;
        int("num_minibatches", self.num_minibatches as u64, 1 << 20)?;
        int("total_steps", self.total_steps, MAX_TOTAL_STEPS)?;
        int("update_epochs", self.update_epochs as u64, 1000)?;
        int("hidden", self.hidden as u64, MAX_HIDDEN as u64)?;
        int("env_threads", self.env_threads as u64, 1024)?;
        let batch = self.num_envs * self.num_steps;
        if self.num_minibatches * 4 > batch {
            return Err(format!(
                "invalid value {} for option `num_minibatches`: each minibatch needs at least 4 of the num_envs × \
                 num_steps = {batch} steps of an update (allowed 1..={})",
                self.num_minibatches,
                batch / 4
            ));
        }
        let within = |name: &str, v: f64, lo: f64, hi: f64, low_open: bool| {
            let ok = v.is_finite() && v <= hi && if low_open { v > lo } else { v >= lo };
            if ok { Ok(()) } else { Err(format!("invalid value {v} for option `{name}`: allowed {lo}..={hi}")) }
        };
        within("gamma", self.gamma, 0.0, 1.0, true)?;
        within("gae_lambda", self.gae_lambda, 0.0, 1.0, false)?;
        within("learning_rate", self.learning_rate, 0.0, 1.0, true)?;
        within("clip_coef", self.clip_coef, 0.0, 10.0, true)?;
        within("ent_coef", self.ent_coef, 0.0, 1000.0, false)?;
        within("vf_coef", self.vf_coef, 0.0, 1000.0, false)?;
        within("max_grad_norm", self.max_grad_norm, 0.0, 1e9, true)?;
        if self.obs_type != "features" || !matches!(self.network.as_str(), "auto" | "mlp") {
            return Err("the Rust learner trains the MLP on features (obs_type 'features'); the pixel recipes \
                        train with python -m chopperscape.learn.train"
                .into());
        }
        if self.aux_coef != 0.0 || !self.teacher.is_empty() || self.augment != "none" {
            return Err("aux_coef, teacher and augment are for CNN recipes (pixel observations)".into());
        }
        for name in self.env_options.keys() {
            if matches!(name.as_str(), "obs_type" | "num_threads" | "copy" | "autoreset_mode" | "render_mode") {
                return Err(format!("env option `{name}` is not taken: the recipe sets it itself"));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_schedule_decays_linearly_to_its_floor() {
        let r = Recipe::fast();
        assert_eq!(r.learning_rate_at(0), 1e-3);
        assert!((r.learning_rate_at(1_500_000) - 5e-4).abs() < 1e-12);
        assert!((r.learning_rate_at(2_900_000) - 5e-5).abs() < 1e-12);
        assert!((r.learning_rate_at(4_000_000) - 5e-5).abs() < 1e-12);
    }

    #[test]
    fn a_setting_out_of_range_is_named() {
        let r = Recipe { num_minibatches: 10_000, ..Recipe::fast() };
        assert!(r.check().unwrap_err().contains("num_minibatches"));
        let r = Recipe { obs_type: "grayscale".into(), ..Recipe::fast() };
        assert!(r.check().unwrap_err().contains("features"));
        Recipe::fast().check().unwrap();
    }
}
