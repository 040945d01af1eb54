//! Action and observation spaces, as Gymnasium declares them.

/// `Discrete(n)`: the integers `0..n`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Discrete {
    /// Number of actions.
    pub n: usize,
}

impl Discrete {
    /// Whether `a` is one of the actions.
    pub fn contains(&self, a: i64) -> bool {
        usize::try_from(a).is_ok_and(|a| a < self.n)
    }
}

/// Element type of an observation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Dtype {
    /// `uint8`.
    U8,
    /// `float32`.
    F32,
}

impl Dtype {
    /// numpy's name for it.
    pub fn as_str(self) -> &'static str {
        match self {
            Dtype::U8 => "uint8",
            Dtype::F32 => "float32",
        }
    }
}

/// The bounds of a [`BoxSpace`], stored without a value per element when they repeat.
#[derive(Clone, Debug, PartialEq)]
pub enum Bounds {
    /// Every element shares `[low, high]` (pixel observations): two numbers, whatever the shape.
    Uniform {
        /// Lower bound of every element.
        low: f32,
        /// Upper bound of every element.
        high: f32,
    },
    /// One period of per-element bounds, repeated along the row-major elements (the features vector, repeated
    /// once per stacked frame). The period's length divides the number of elements.
    Repeated {
        /// Lower bounds of one period.
        low: Vec<f32>,
        /// Upper bounds of one period.
        high: Vec<f32>,
    },
}

/// `Box(low, high, shape, dtype)`. The bounds ([`Bounds`]) cost no memory per element: uniform bounds are two
/// numbers and repeated bounds one period.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxSpace {
    /// Shape, row-major.
    pub shape: Vec<usize>,
    /// Element type.
    pub dtype: Dtype,
    /// Lower and upper bounds.
    pub bounds: Bounds,
}

impl BoxSpace {
    /// A box whose every element shares the bounds `[low, high]`.
    pub fn uniform(shape: Vec<usize>, dtype: Dtype, low: f32, high: f32) -> BoxSpace {
        BoxSpace { shape, dtype, bounds: Bounds::Uniform { low, high } }
    }

    /// A box whose bounds are `low` and `high` (one period, of equal lengths that divide the number of
    /// elements) repeated along the elements.
    ///
    /// # Panics
    /// If the period is empty, the two lengths differ, or the period does not divide the number of elements.
    pub fn repeated(shape: Vec<usize>, dtype: Dtype, low: Vec<f32>, high: Vec<f32>) -> BoxSpace {
        let n: usize = shape.iter().product();
        assert!(
            !low.is_empty() && low.len() == high.len() && n % low.len() == 0,
            "bounds period must divide the shape"
        );
        BoxSpace { shape, dtype, bounds: Bounds::Repeated { low, high } }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// Whether the space has no elements (never, for ChopperScape).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The bounds `(low, high)` of element `i` (row-major).
    pub fn bounds_of(&self, i: usize) -> (f32, f32) {
        match &self.bounds {
            Bounds::Uniform { low, high } => (*low, *high),
            Bounds::Repeated { low, high } => (low[i % low.len()], high[i % high.len()]),
        }
    }

    /// Whether every element of `values` lies within its bounds (and the count matches). NaN lies nowhere.
    pub fn contains<T: Copy + Into<f32>>(&self, values: &[T]) -> bool {
        values.len() == self.len()
            && values.iter().enumerate().all(|(i, &v)| {
                let (lo, hi) = self.bounds_of(i);
                let v: f32 = v.into();
                lo <= v && v <= hi
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_bounds_cost_no_memory_per_element() {
        // A 4096 × 4096 × 192 box would need 25 GiB of f32 bounds if they were stored per element.
        let space = BoxSpace::uniform(vec![4096, 4096, 192], Dtype::F32, 0.0, 1.0);
        assert_eq!(space.bounds, Bounds::Uniform { low: 0.0, high: 1.0 });
        assert_eq!(space.bounds_of(space.len() - 1), (0.0, 1.0));
    }

    #[test]
    fn repeated_bounds_repeat_along_the_elements() {
        let space = BoxSpace::repeated(vec![6], Dtype::F32, vec![0.0, -1.0], vec![1.0, 1.0]);
        assert_eq!(space.bounds_of(3), (-1.0, 1.0));
        assert!(space.contains(&[0.5f32, -0.5, 0.0, 1.0, 1.0, -1.0]));
        assert!(!space.contains(&[-0.5f32, 0.0, 0.0, 0.0, 0.0, 0.0]));
        assert!(!space.contains(&[f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0]));
    }
}
