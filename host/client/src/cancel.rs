//! Cancelling long work: a [`Cancel`] token a front end (a Ctrl-C handler, a page's Abort
//! button, a timer of a user's program) sets and the library checks.
//!
//! Invariants: a token is cheap to clone and every clone sees the same flag; a token made with
//! [`Cancel::child`] is cancelled when it or any ancestor is (cancelling a child never cancels
//! its parent), so one operation of a long-running program can be aborted without ending the
//! program. [`ctrl_c`] is the process's root token: a front end's signal handler sets it, and
//! tokens made by [`Cancel::on_ctrl_c`] are its children, so Ctrl-C stops whatever checks them.
//! [`Cancel::default`] is detached (as [`Cancel::detached`]): nothing but its own
//! [`Cancel::cancel`] reaches it.
//!
//! What checks it: [`crate::Client`] between the messages of an experiment (it then sends
//! `Stop`, lets the device end the test and returns [`crate::ClientError::Cancelled`]), the
//! telemetry session between batches, and the tune procedure between its steps.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

/// A cancellation token (see the module header).
#[derive(Debug, Clone)]
pub struct Cancel {
    flag: Arc<AtomicBool>,
    parent: Option<Box<Cancel>>,
}

impl Cancel {
    /// A token no one else can cancel: neither Ctrl-C nor any other token reaches it.
    #[must_use]
    pub fn detached() -> Self {
        Self {
            flag: Arc::new(AtomicBool::new(false)),
            parent: None,
        }
    }

    /// A child of [`ctrl_c`]: cancelled by Ctrl-C (once a front end's signal handler cancels
    /// [`ctrl_c`]) and by its own [`Cancel::cancel`].
    #[must_use]
    pub fn on_ctrl_c() -> Self {
        ctrl_c().child()
    }

    /// A new token cancelled with this one (and by its own [`Cancel::cancel`]).
    #[must_use]
    pub fn child(&self) -> Self {
        Self {
            flag: Arc::new(AtomicBool::new(false)),
            parent: Some(Box::new(self.clone())),
        }
    }

    /// Cancels this token, its clones and its children.
    pub fn cancel(&self) {
        self.flag.store(true, Ordering::Relaxed);
    }

    /// Whether this token or an ancestor was cancelled.
    #[must_use]
    pub fn is_cancelled(&self) -> bool {
        self.flag.load(Ordering::Relaxed) || self.parent.as_ref().is_some_and(|p| p.is_cancelled())
    }
}

impl Default for Cancel {
    /// A detached token ([`Cancel::detached`]): Ctrl-C does not reach it.
    fn default() -> Self {
        Self::detached()
    }
}

/// The process's root token, set by a front end's Ctrl-C handler (this crate installs none).
pub fn ctrl_c() -> &'static Cancel {
    static ROOT: OnceLock<Cancel> = OnceLock::new();
    ROOT.get_or_init(Cancel::detached)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_child_follows_its_parent_but_not_the_other_way() {
        let parent = Cancel::detached();
        let child = parent.child();
        let sibling = parent.child();
        assert!(!child.is_cancelled());
        child.cancel();
        assert!(child.is_cancelled());
        assert!(!parent.is_cancelled() && !sibling.is_cancelled());
        parent.cancel();
        assert!(sibling.is_cancelled());
    }

    #[test]
    fn a_default_token_is_detached_from_ctrl_c() {
        assert!(Cancel::default().parent.is_none());
        assert!(Cancel::on_ctrl_c().parent.is_some());
    }

    #[test]
    fn clones_share_the_flag() {
        let a = Cancel::detached();
        let b = a.clone();
        b.cancel();
        assert!(a.is_cancelled());
    }
}
