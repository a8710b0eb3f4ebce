//! Locking shared state.

use std::sync::Mutex;

/// Lock a mutex, recovering the data if a panicking thread poisoned it (the
/// state stays consistent: every critical section only assigns fields).
pub fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}
