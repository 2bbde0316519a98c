//! A value kept with the key it was computed from, so that a computation from an equal key reuses
//! it instead of repeating it.
//!
//! The input-reading rows run once with the table's inputs as they are and again under each
//! deliberate error ([`crate::input_rows`]). A part of a row that reads only some of the inputs
//! (say the step slacks of the SGD proof, which read L_F, σ² and c) is a function of those values
//! alone; keyed by them, an error that leaves them equal gets the kept value, which is exactly the
//! value the computation would return.

use std::borrow::Cow;

/// `value = f(&key)` for the `f` given to [`Keyed::new`].
#[derive(Debug, Clone)]
pub struct Keyed<K, V> {
    key: K,
    value: V,
}

impl<K: PartialEq, V: Clone> Keyed<K, V> {
    /// Compute `f(&key)` and keep it with `key`.
    pub fn new(key: K, f: impl FnOnce(&K) -> V) -> Self {
        let value = f(&key);
        Keyed { key, value }
    }

    /// The value for `key`: the kept one if `key` equals the kept key, else `f(key)`. `f` must be
    /// the function given to [`Keyed::new`] (the caller's contract: the value depends on the key
    /// only).
    pub fn get(&self, key: &K, f: impl FnOnce(&K) -> V) -> Cow<'_, V> {
        if *key == self.key {
            Cow::Borrowed(&self.value)
        } else {
            Cow::Owned(f(key))
        }
    }

    /// The key the kept value was computed from.
    pub fn key(&self) -> &K {
        &self.key
    }

    /// The kept value.
    pub fn value(&self) -> &V {
        &self.value
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn an_equal_key_reuses_and_another_key_computes() {
        let calls = Cell::new(0);
        let square = |k: &i64| {
            calls.set(calls.get() + 1);
            k * k
        };
        let kept = Keyed::new(3, square);
        assert_eq!((*kept.key(), *kept.value(), calls.get()), (3, 9, 1));
        assert_eq!(*kept.get(&3, square), 9);
        assert_eq!(calls.get(), 1, "an equal key must not recompute");
        assert_eq!(*kept.get(&4, square), 16);
        assert_eq!(calls.get(), 2, "another key must compute");
    }
}
