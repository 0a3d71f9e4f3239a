//! Work handed to rayon's threads under the limits and roots of the thread that asks for it.
//!
//! A script's time limit, memory limit, output root and point store are set on the thread
//! that runs it (thread-local, so that hosts on different threads do not share them). Work
//! that thread runs in parallel (the simulations of a TR-NEWS pass, the points of a delayed
//! sweep) goes through [`Context`], which carries them onto each worker for the length of its
//! task: a time limit stops every simulation of a parallel pass, a write from a worker is
//! confined to the script's output root. A panic on a worker of a guarded script run is
//! recorded there, not printed, and reaches the script's thread with its location.

use crate::budget::Limits;
use crate::io::OutputRoot;
use crate::sweep::Store;
use rayon::prelude::*;
use std::sync::Arc;

/// The thread-local settings a task carries onto the thread that runs it.
#[derive(Clone, Debug)]
pub struct Context {
    limits: Limits,
    root: Option<OutputRoot>,
    store: Option<Arc<Store>>,
    guarded: bool,
}

impl Context {
    /// The settings of the current thread.
    pub fn current() -> Context {
        Context {
            limits: Limits::current(),
            root: crate::io::active_root(),
            store: crate::sweep::active_store(),
            guarded: crate::guard::is_guarded(),
        }
    }

    /// Runs `f` with these settings on the current thread; its own are restored afterwards.
    pub fn within<T>(&self, f: impl FnOnce() -> T) -> T {
        let settled = || {
            self.limits.within(|| {
                crate::sweep::with_store(self.store.clone(), || match &self.root {
                    Some(root) => root.within(f),
                    None => crate::io::without_root(f),
                })
            })
        };
        if self.guarded {
            crate::guard::on_worker(settled)
        } else {
            settled()
        }
    }
}

/// `f` over `items` in parallel, results in order, each call under the caller's [`Context`];
/// the first error stops the others from starting and is returned.
pub fn try_map<I: Sync, T: Send, E: Send>(
    items: &[I],
    f: impl Fn(&I) -> Result<T, E> + Sync,
) -> Result<Vec<T>, E> {
    let context = Context::current();
    items
        .par_iter()
        .map(|item| context.within(|| f(item)))
        .collect()
}

/// `f` over `items` in parallel, each call under the caller's [`Context`]; the first error
/// stops the others from starting and is returned.
pub fn try_for_each<I: Sync, E: Send>(
    items: &[I],
    f: impl Fn(&I) -> Result<(), E> + Sync,
) -> Result<(), E> {
    let context = Context::current();
    items
        .par_iter()
        .try_for_each(|item| context.within(|| f(item)))
}
