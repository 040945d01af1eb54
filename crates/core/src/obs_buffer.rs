//! Where an observation is stored: owned ([`Observation`]) for convenience, or a caller-owned buffer
//! ([`ObsBufMut`]) written on the hot path. What goes into them is made by the pipeline in `obs_pipeline.rs`.

use crate::spaces::Dtype;

/// The elements of an owned observation.
#[derive(Clone, Debug, PartialEq)]
pub enum ObsData {
    /// `uint8` elements (`rgb`, `grayscale`).
    U8(Vec<u8>),
    /// `float32` elements (`rgb_float`, `features`).
    F32(Vec<f32>),
}

/// An owned observation: a shape and row-major elements.
#[derive(Clone, Debug, PartialEq)]
pub struct Observation {
    /// Shape, row-major (for example `[600, 800, 3]`).
    pub shape: Vec<usize>,
    /// Elements.
    pub data: ObsData,
}

impl Observation {
    /// An all-zero observation of this shape and type.
    pub fn zeros(shape: Vec<usize>, dtype: Dtype) -> Observation {
        let n = shape.iter().product();
        let data = match dtype {
            Dtype::U8 => ObsData::U8(vec![0; n]),
            Dtype::F32 => ObsData::F32(vec![0.0; n]),
        };
        Observation { shape, data }
    }

    /// A mutable view, to write into.
    pub fn as_buf_mut(&mut self) -> ObsBufMut<'_> {
        match &mut self.data {
            ObsData::U8(v) => ObsBufMut::U8(v),
            ObsData::F32(v) => ObsBufMut::F32(v),
        }
    }

    /// The `u8` elements, if that is the type.
    pub fn as_u8(&self) -> Option<&[u8]> {
        match &self.data {
            ObsData::U8(v) => Some(v),
            ObsData::F32(_) => None,
        }
    }

    /// The `f32` elements, if that is the type.
    pub fn as_f32(&self) -> Option<&[f32]> {
        match &self.data {
            ObsData::F32(v) => Some(v),
            ObsData::U8(_) => None,
        }
    }
}

/// A caller-owned buffer the environment writes one observation into.
#[derive(Debug)]
pub enum ObsBufMut<'a> {
    /// For `uint8` observations.
    U8(&'a mut [u8]),
    /// For `float32` observations.
    F32(&'a mut [f32]),
}

impl ObsBufMut<'_> {
    /// Number of elements.
    pub fn len(&self) -> usize {
        match self {
            ObsBufMut::U8(b) => b.len(),
            ObsBufMut::F32(b) => b.len(),
        }
    }

    /// Whether the buffer is empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Element type.
    pub fn dtype(&self) -> Dtype {
        match self {
            ObsBufMut::U8(_) => Dtype::U8,
            ObsBufMut::F32(_) => Dtype::F32,
        }
    }
}
