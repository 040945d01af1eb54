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

/// `Box(low, high, shape, dtype)`. `low` and `high` hold one value for every element (row-major).
#[derive(Clone, Debug, PartialEq)]
pub struct BoxSpace {
    /// Shape, row-major.
    pub shape: Vec<usize>,
    /// Element type.
    pub dtype: Dtype,
    /// Lower bound of each element.
    pub low: Vec<f32>,
    /// Upper bound of each element.
    pub high: Vec<f32>,
}

impl BoxSpace {
    /// A box whose every element shares the bounds `[low, high]`.
    pub fn uniform(shape: Vec<usize>, dtype: Dtype, low: f32, high: f32) -> BoxSpace {
        let n = shape.iter().product();
        BoxSpace { shape, dtype, low: vec![low; n], high: vec![high; n] }
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// Whether the space has no elements (never, for ChopperScape).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether every element of `values` lies within its bounds (and the count matches).
    pub fn contains<T: Copy + Into<f32>>(&self, values: &[T]) -> bool {
        values.len() == self.len()
            && values.iter().zip(self.low.iter().zip(&self.high)).all(|(&v, (&lo, &hi))| {
                let v: f32 = v.into();
                lo <= v && v <= hi
            })
    }
}
