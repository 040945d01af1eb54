//! The batch's own worker pool: built on first use, and rebuilt in a forked child.
//!
//! A pool's threads do not survive `fork()`: a child that inherited a built pool would wait forever on
//! workers that do not exist. Python's `AsyncVectorEnv`, Stable-Baselines3 and data loaders fork, so the
//! pool is built lazily (never at construction or import) and remembers the process that built it; a
//! different process id means a fork happened, and the child builds its own pool.

use rayon::{ThreadPool, ThreadPoolBuilder};

use crate::error::BatchError;

/// A lazily built `rayon` pool of `threads` workers, private to one vector env.
#[derive(Debug)]
pub(crate) struct LazyPool {
    threads: usize,
    built: Option<(u32, ThreadPool)>,
}

impl LazyPool {
    pub(crate) fn new(threads: usize) -> LazyPool {
        LazyPool { threads, built: None }
    }

    /// The pool, built now if this process has none yet.
    pub(crate) fn get(&mut self) -> Result<&ThreadPool, BatchError> {
        let pid = std::process::id();
        if let Some((owner, pool)) = self.built.take() {
            if owner == pid {
                return Ok(&self.built.insert((owner, pool)).1);
            }
            // Inherited across fork(): its workers do not exist in this process, so dropping it could wait
            // on them. Leak it instead (a few small allocations, once per fork).
            std::mem::forget(pool);
        }
        let pool = ThreadPoolBuilder::new()
            .num_threads(self.threads)
            .thread_name(|i| format!("chopperscape-vector-{i}"))
            .build()
            .map_err(|e| BatchError::ThreadPool { threads: self.threads, reason: e.to_string() })?;
        Ok(&self.built.insert((pid, pool)).1)
    }
}

impl Clone for LazyPool {
    /// A clone gets its own pool, built when it is first used.
    fn clone(&self) -> LazyPool {
        LazyPool::new(self.threads)
    }
}
