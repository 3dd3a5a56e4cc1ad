//! Fixed-length arrays read with their length checked.
//!
//! serde's impl for `[T; N]` visits N elements and stops: the toml deserializer then
//! never looks at what follows, so `velocity = [0, 0, -5, 1]` was read as [0, 0, -5]
//! and the fourth component silently dropped. These visitors read the whole array and
//! refuse any other length ("invalid length 4, expected an array of 3 numbers", which
//! the scene reports as a wrong type at the value).

use serde::de::{Deserialize, Deserializer, Error, IgnoredAny, SeqAccess, Visitor};
use std::fmt;
use std::marker::PhantomData;

struct Exact<T, const N: usize>(PhantomData<T>);

impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for Exact<T, N> {
    type Value = [T; N];

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "an array of {N} numbers")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[T; N], A::Error> {
        let mut items = Vec::with_capacity(N);
        while items.len() < N {
            match seq.next_element::<T>()? {
                Some(x) => items.push(x),
                None => break,
            }
        }
        let mut len = items.len();
        while seq.next_element::<IgnoredAny>()?.is_some() {
            len += 1;
        }
        if len != N {
            return Err(A::Error::invalid_length(len, &self));
        }
        items
            .try_into()
            .map_err(|_| A::Error::invalid_length(len, &self))
    }
}

/// `[T; N]`, exactly N elements.
pub fn array<'de, D, T, const N: usize>(d: D) -> Result<[T; N], D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    d.deserialize_seq(Exact::<T, N>(PhantomData))
}

/// `Option<[T; N]>` for an optional key (use with `#[serde(default)]`).
pub fn option<'de, D, T, const N: usize>(d: D) -> Result<Option<[T; N]>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    array(d).map(Some)
}

/// `Vec<[T; N]>`: a list of fixed-length rows (e.g. curve points `[[t, v], ...]`).
pub fn rows<'de, D, T, const N: usize>(d: D) -> Result<Vec<[T; N]>, D::Error>
where
    D: Deserializer<'de>,
    T: Deserialize<'de>,
{
    struct Row<T, const N: usize>([T; N]);
    impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Row<T, N> {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            array(d).map(Row)
        }
    }
    let rows: Vec<Row<T, N>> = Vec::deserialize(d)?;
    Ok(rows.into_iter().map(|r| r.0).collect())
}
