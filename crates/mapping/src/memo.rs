//! Results of pure set-up functions kept for the process, keyed by the text of their
//! inputs ([`Memo`]): a process that makes many maps of the same data (the experiments:
//! 71 maps of a few energy tables) computes each map's window kernel, gain tables and
//! scoring region once per distinct input instead of once per map.
//!
//! The key is the `Debug` text of everything the function reads (Rust prints an `f64`
//! as the shortest text that reads back to the same bits, so equal keys mean equal
//! inputs), and the value is what the function returned, handed out as a clone: the
//! results are the same bytes as without the memo. A memo keeps its last
//! [`MEMO_SLOTS`] entries; two threads asking for a missing key at once both compute it.

use std::sync::Mutex;

/// Entries a memo keeps (the least recently made go first).
pub const MEMO_SLOTS: usize = 16;

/// A small process-wide memo of one function's results.
pub struct Memo<T> {
    slots: Mutex<Vec<(String, T)>>,
}

impl<T: Clone> Default for Memo<T> {
    fn default() -> Memo<T> {
        Memo::new()
    }
}

impl<T: Clone> Memo<T> {
    /// An empty memo (for a `static`).
    pub const fn new() -> Memo<T> {
        Memo {
            slots: Mutex::new(Vec::new()),
        }
    }

    /// The value for `key`, made by `make` when the memo does not hold it (an error is
    /// returned and not kept).
    pub fn get_or<E>(&self, key: String, make: impl FnOnce() -> Result<T, E>) -> Result<T, E> {
        if let Some(v) = self
            .lock()
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, v)| v.clone())
        {
            return Ok(v);
        }
        let v = make()?;
        let mut slots = self.lock();
        if !slots.iter().any(|(k, _)| *k == key) {
            if slots.len() >= MEMO_SLOTS {
                slots.remove(0);
            }
            slots.push((key, v.clone()));
        }
        Ok(v)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<(String, T)>> {
        // a panic while holding the lock leaves a consistent Vec: keep using it
        self.slots.lock().unwrap_or_else(|e| e.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_memo_computes_each_key_once_and_keeps_its_last_slots() {
        static M: Memo<u64> = Memo::new();
        let calls = std::sync::atomic::AtomicUsize::new(0);
        let f = |x: u64| {
            M.get_or::<()>(format!("{x}"), || {
                calls.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                Ok(x * 2)
            })
            .unwrap()
        };
        assert_eq!((f(1), f(1), f(2)), (2, 2, 4));
        assert_eq!(calls.load(std::sync::atomic::Ordering::SeqCst), 2);
        for x in 10..10 + MEMO_SLOTS as u64 {
            f(x);
        }
        let before = calls.load(std::sync::atomic::Ordering::SeqCst);
        assert_eq!(f(1), 2); // pushed out: made again
        assert_eq!(calls.load(std::sync::atomic::Ordering::SeqCst), before + 1);
        assert!(M
            .get_or("err".to_string(), || Err::<u64, &str>("no"))
            .is_err());
        assert_eq!(M.get_or::<()>("err".to_string(), || Ok(7)).unwrap(), 7);
    }
}
