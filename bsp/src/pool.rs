//! Per-thread recycling of working memory: one bounded pool type.
//!
//! The kernels build and drop many small structures (arenas, polygons,
//! index buffers, the working memory of a mesh pass), each about as large
//! as the last. Instead of freeing that memory, a dropped structure hands
//! it to a [`Pool`] of its thread, and the next one takes it back, so that
//! after a warm-up most operations allocate nothing.
//!
//! A pool is declared once per kind of value, next to the code that uses
//! it, and reached through [`PerThread`]:
//!
//! ```ignore
//! thread_local! {
//!     static SPARE: Pool<Vec<u32>> = const { Pool::new(2048) };
//! }
//! let buffer = SPARE.take().unwrap_or_default();
//! SPARE.keep(buffer);
//! ```
//!
//! A pool holds at most the number of values it was made with; a value
//! given to a full pool, to a pool in use (a reentrant call), or while the
//! thread is ending is dropped, and a take from an empty one gets `None`.
//! The pool neither clears nor checks what it keeps: the caller empties a
//! value before [`PerThread::keep`], and decides whether a value taken back
//! is large enough.

use std::cell::RefCell;
use std::thread::LocalKey;

/// A bounded stack of spare values, for one thread (declare it in a
/// `thread_local!` and use it through [`PerThread`]).
pub(crate) struct Pool<T> {
    spare: RefCell<Vec<T>>,
    max: usize,
}

impl<T> Pool<T> {
    /// An empty pool that keeps at most `max` values.
    #[must_use]
    pub(crate) const fn new(max: usize) -> Self {
        Self {
            spare: RefCell::new(Vec::new()),
            max,
        }
    }
}

/// The operations on the [`Pool`] of the current thread.
pub(crate) trait PerThread<T> {
    /// The value kept last, if any.
    fn take(&'static self) -> Option<T>;

    /// Keeps `value` for a later [`PerThread::take`] while there is room;
    /// else it is dropped.
    fn keep(&'static self, value: T);

    /// Keeps the values `values` yields while there is room, and stops
    /// asking for more when the pool is full (what is left is the caller's
    /// to free).
    fn keep_while_room(&'static self, values: impl Iterator<Item = T>);
}

impl<T: 'static> PerThread<T> for LocalKey<Pool<T>> {
    #[inline]
    fn take(&'static self) -> Option<T> {
        self.try_with(|pool| pool.spare.try_borrow_mut().ok()?.pop())
            .ok()
            .flatten()
    }

    #[inline]
    fn keep(&'static self, value: T) {
        let _ = self.try_with(|pool| {
            if let Ok(mut spare) = pool.spare.try_borrow_mut()
                && spare.len() < pool.max
            {
                spare.push(value);
            }
        });
    }

    fn keep_while_room(&'static self, values: impl Iterator<Item = T>) {
        let _ = self.try_with(|pool| {
            if let Ok(mut spare) = pool.spare.try_borrow_mut() {
                for value in values {
                    if spare.len() >= pool.max {
                        break;
                    }
                    spare.push(value);
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::{PerThread, Pool};

    thread_local! {
        static TWO: Pool<u32> = const { Pool::new(2) };
    }

    #[test]
    fn keeps_at_most_its_bound_last_in_first_out() {
        TWO.keep(1);
        TWO.keep(2);
        TWO.keep(3);
        assert_eq!(TWO.take(), Some(2));
        TWO.keep_while_room([4, 5, 6].into_iter());
        assert_eq!(TWO.take(), Some(4));
        assert_eq!(TWO.take(), Some(1));
        assert_eq!(TWO.take(), None);
    }
}
