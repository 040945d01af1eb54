//! The five actions of `Discrete(5)`.

use crate::error::Error;

/// One of the five actions; the discriminant is the action index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[repr(u8)]
pub enum Action {
    /// 0: x += 5.
    Right = 0,
    /// 1: x −= 5.
    Left = 1,
    /// 2: y += 5.
    Down = 2,
    /// 3: y −= 5.
    Up = 3,
    /// 4: nothing moves by the agent's hand.
    #[default]
    Noop = 4,
}

/// Number of actions: the `n` of `Discrete(5)`.
pub const N_ACTIONS: usize = 5;

/// `get_action_meanings()`: the name of each action, by index.
pub const ACTION_MEANINGS: [&str; N_ACTIONS] = ["Right", "Left", "Down", "Up", "Do Nothing"];

impl Action {
    /// Every action, by index.
    pub const ALL: [Action; N_ACTIONS] = [Action::Right, Action::Left, Action::Down, Action::Up, Action::Noop];

    /// The chopper's displacement `(dx, dy)` in pixels.
    #[inline]
    pub fn delta(self) -> (i32, i32) {
        use crate::consts::CHOPPER_SPEED as S;
        match self {
            Action::Right => (S, 0),
            Action::Left => (-S, 0),
            Action::Down => (0, S),
            Action::Up => (0, -S),
            Action::Noop => (0, 0),
        }
    }

    /// The action's index.
    pub fn index(self) -> usize {
        self as usize
    }

    /// The action's name, as in [`ACTION_MEANINGS`].
    pub fn meaning(self) -> &'static str {
        ACTION_MEANINGS[self.index()]
    }
}

impl TryFrom<i64> for Action {
    type Error = Error;
    /// # Errors
    /// [`Error::InvalidAction`] for anything outside `0..=4`.
    fn try_from(a: i64) -> Result<Action, Error> {
        usize::try_from(a).ok().and_then(|i| Action::ALL.get(i).copied()).ok_or(Error::InvalidAction(a))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_action_does_what_its_name_says() {
        assert_eq!(Action::try_from(0).unwrap().delta(), (5, 0));
        assert_eq!(Action::try_from(1).unwrap().delta(), (-5, 0));
        assert_eq!(Action::try_from(2).unwrap().delta(), (0, 5));
        assert_eq!(Action::try_from(3).unwrap().delta(), (0, -5));
        assert_eq!(Action::try_from(4).unwrap().delta(), (0, 0));
        for a in Action::ALL {
            assert_eq!(a.meaning(), ACTION_MEANINGS[a.index()]);
        }
    }

    #[test]
    fn invalid_actions_are_rejected_with_the_allowed_range() {
        for a in [-1, 5, 6, i64::MAX] {
            let err = Action::try_from(a).unwrap_err().to_string();
            assert!(err.contains(&a.to_string()) && err.contains("0..=4"), "{err}");
        }
    }
}
