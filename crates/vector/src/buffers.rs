//! Where a batch writes: [`BatchMut`], views of caller-owned arrays (numpy arrays, for Python), and
//! [`Buffers`], owned arrays for Rust callers.

use chopperscape::{Cause, Dtype, ObsBufMut};

use crate::error::BatchError;

/// `cause` code of an environment whose episode did not terminate this step.
pub const CAUSE_NONE: u8 = 0;
/// `cause` code of a termination by a bird (or an alien, or a missile).
pub const CAUSE_BIRD: u8 = 1;
/// `cause` code of a termination by running out of fuel.
pub const CAUSE_FUEL: u8 = 2;
/// The name of each `cause` code, by code: `""`, `"bird"`, `"fuel"`.
pub const CAUSE_NAMES: [&str; 3] = ["", "bird", "fuel"];

/// The `cause` code of a termination cause.
pub fn cause_code(cause: Option<Cause>) -> u8 {
    match cause {
        None => CAUSE_NONE,
        Some(Cause::Bird) => CAUSE_BIRD,
        Some(Cause::Fuel) => CAUSE_FUEL,
    }
}

/// Mutable views of one batch's outputs, environment `i` at index `i` (observations: elements
/// `i·obs_len .. (i+1)·obs_len`). The views may be caller-owned memory such as numpy arrays.
#[derive(Debug)]
pub struct BatchMut<'a> {
    /// Observations, `num_envs · obs_len` elements of the observation's type.
    pub observations: ObsBufMut<'a>,
    /// Rewards.
    pub rewards: &'a mut [f32],
    /// Whether each episode ended by the rules this step.
    pub terminated: &'a mut [bool],
    /// Whether each episode was cut off at `max_episode_steps` this step.
    pub truncated: &'a mut [bool],
    /// Fuel left.
    pub fuel: &'a mut [u32],
    /// Lives left.
    pub lives: &'a mut [u32],
    /// Why each episode terminated ([`CAUSE_NONE`], [`CAUSE_BIRD`], [`CAUSE_FUEL`]).
    pub cause: &'a mut [u8],
    /// `SAME_STEP` only: the last observation of each episode that ended this step (the others are left as
    /// they were), `num_envs · obs_len` elements.
    pub final_observations: Option<ObsBufMut<'a>>,
}

impl<'a> BatchMut<'a> {
    /// Checks every length and element type against `n` environments of `obs_len` elements of `dtype`.
    pub(crate) fn check(&self, n: usize, obs_len: usize, dtype: Dtype) -> Result<(), BatchError> {
        let obs = |buffer: &'static str, b: &ObsBufMut<'_>| {
            if b.len() == n * obs_len && b.dtype() == dtype {
                Ok(())
            } else {
                Err(BatchError::BufferSize {
                    buffer,
                    expected: n * obs_len,
                    expected_dtype: dtype.as_str(),
                    got: b.len(),
                    got_dtype: b.dtype().as_str(),
                })
            }
        };
        let scalar = |buffer: &'static str, len: usize, dtype: &'static str| {
            if len == n {
                Ok(())
            } else {
                Err(BatchError::BufferSize { buffer, expected: n, expected_dtype: dtype, got: len, got_dtype: dtype })
            }
        };
        obs("observations", &self.observations)?;
        if let Some(f) = &self.final_observations {
            obs("final_observations", f)?;
        }
        scalar("rewards", self.rewards.len(), "float32")?;
        scalar("terminated", self.terminated.len(), "bool")?;
        scalar("truncated", self.truncated.len(), "bool")?;
        scalar("fuel", self.fuel.len(), "uint32")?;
        scalar("lives", self.lives.len(), "uint32")?;
        scalar("cause", self.cause.len(), "uint8")
    }

    /// Splits after the first `envs` environments.
    pub(crate) fn split_at(self, envs: usize, obs_len: usize) -> (BatchMut<'a>, BatchMut<'a>) {
        let (o1, o2) = split_obs(self.observations, envs * obs_len);
        let (f1, f2) = match self.final_observations {
            Some(f) => {
                let (a, b) = split_obs(f, envs * obs_len);
                (Some(a), Some(b))
            }
            None => (None, None),
        };
        let (r1, r2) = self.rewards.split_at_mut(envs);
        let (te1, te2) = self.terminated.split_at_mut(envs);
        let (tr1, tr2) = self.truncated.split_at_mut(envs);
        let (fu1, fu2) = self.fuel.split_at_mut(envs);
        let (l1, l2) = self.lives.split_at_mut(envs);
        let (c1, c2) = self.cause.split_at_mut(envs);
        (
            BatchMut {
                observations: o1,
                rewards: r1,
                terminated: te1,
                truncated: tr1,
                fuel: fu1,
                lives: l1,
                cause: c1,
                final_observations: f1,
            },
            BatchMut {
                observations: o2,
                rewards: r2,
                terminated: te2,
                truncated: tr2,
                fuel: fu2,
                lives: l2,
                cause: c2,
                final_observations: f2,
            },
        )
    }
}

fn split_obs(b: ObsBufMut<'_>, at: usize) -> (ObsBufMut<'_>, ObsBufMut<'_>) {
    match b {
        ObsBufMut::U8(s) => {
            let (a, b) = s.split_at_mut(at);
            (ObsBufMut::U8(a), ObsBufMut::U8(b))
        }
        ObsBufMut::F32(s) => {
            let (a, b) = s.split_at_mut(at);
            (ObsBufMut::F32(a), ObsBufMut::F32(b))
        }
    }
}

/// Elements of a batch's observations, read-only.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Observations<'a> {
    /// `uint8` elements (`rgb`, `grayscale`).
    U8(&'a [u8]),
    /// `float32` elements (`rgb_float`, `features`).
    F32(&'a [f32]),
}

#[derive(Clone, Debug, PartialEq)]
enum ObsVec {
    U8(Vec<u8>),
    F32(Vec<f32>),
}

impl ObsVec {
    fn zeros(n: usize, dtype: Dtype) -> ObsVec {
        match dtype {
            Dtype::U8 => ObsVec::U8(vec![0; n]),
            Dtype::F32 => ObsVec::F32(vec![0.0; n]),
        }
    }

    fn as_mut(&mut self) -> ObsBufMut<'_> {
        match self {
            ObsVec::U8(v) => ObsBufMut::U8(v),
            ObsVec::F32(v) => ObsBufMut::F32(v),
        }
    }

    fn as_ref(&self) -> Observations<'_> {
        match self {
            ObsVec::U8(v) => Observations::U8(v),
            ObsVec::F32(v) => Observations::F32(v),
        }
    }
}

/// Owned output arrays of a batch, allocated once; [`Buffers::as_mut`] lends them to a step.
#[derive(Clone, Debug, PartialEq)]
pub struct Buffers {
    observations: ObsVec,
    final_observations: Option<ObsVec>,
    /// Rewards.
    pub rewards: Vec<f32>,
    /// Whether each episode ended by the rules.
    pub terminated: Vec<bool>,
    /// Whether each episode was cut off at `max_episode_steps`.
    pub truncated: Vec<bool>,
    /// Fuel left.
    pub fuel: Vec<u32>,
    /// Lives left.
    pub lives: Vec<u32>,
    /// Termination causes ([`CAUSE_NONE`], [`CAUSE_BIRD`], [`CAUSE_FUEL`]).
    pub cause: Vec<u8>,
}

impl Buffers {
    /// Zeroed buffers for `num_envs` observations of `obs_len` elements of `dtype`; `final_observations`
    /// adds the buffer `SAME_STEP` autoreset needs.
    pub fn new(num_envs: usize, obs_len: usize, dtype: Dtype, final_observations: bool) -> Buffers {
        Buffers {
            observations: ObsVec::zeros(num_envs * obs_len, dtype),
            final_observations: final_observations.then(|| ObsVec::zeros(num_envs * obs_len, dtype)),
            rewards: vec![0.0; num_envs],
            terminated: vec![false; num_envs],
            truncated: vec![false; num_envs],
            fuel: vec![0; num_envs],
            lives: vec![0; num_envs],
            cause: vec![CAUSE_NONE; num_envs],
        }
    }

    /// Mutable views of every buffer, for [`crate::VectorEnv::step_into`] and [`crate::VectorEnv::reset_into`].
    pub fn as_mut(&mut self) -> BatchMut<'_> {
        BatchMut {
            observations: self.observations.as_mut(),
            rewards: &mut self.rewards,
            terminated: &mut self.terminated,
            truncated: &mut self.truncated,
            fuel: &mut self.fuel,
            lives: &mut self.lives,
            cause: &mut self.cause,
            final_observations: self.final_observations.as_mut().map(ObsVec::as_mut),
        }
    }

    /// The observations, environment after environment.
    pub fn observations(&self) -> Observations<'_> {
        self.observations.as_ref()
    }

    /// `SAME_STEP` only: the last observation of each episode that ended in the last step.
    pub fn final_observations(&self) -> Option<Observations<'_>> {
        self.final_observations.as_ref().map(ObsVec::as_ref)
    }
}
