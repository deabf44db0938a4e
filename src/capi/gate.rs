//! The way back into the host, and the end of a device.
//!
//! Every call into the host on a device's behalf (its status callback, its
//! frames' completion callbacks) passes the device's `HostGate`. When the
//! host's last reference is released, the device is torn down on a thread
//! of its own (`teardown`): its render thread, presenters and GPUs stop at
//! their next check, which the release waits for a short while only; what
//! takes longer (opening a GPU, compiling a shader) ends in the
//! background, and unloading the library waits for it. Then the gate
//! closes: it waits (briefly) for the host's callbacks running on other
//! threads and lets none start after, so nothing touches host memory the
//! host frees once `anariRelease` returns.

use std::cell::Cell;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::channel;
use std::sync::{Mutex, RwLock};
use std::thread::JoinHandle;
use std::time::Duration;

/// How long a release waits for the device's threads before it returns
/// and leaves the rest to the teardown thread: well within a frame a host
/// can spare.
const RELEASE_WAIT: Duration = Duration::from_millis(200);

thread_local! {
    /// How deep this thread is in calls into the host through a gate.
    static IN_HOST: Cell<u32> = const { Cell::new(0) };
}

#[derive(Default)]
pub struct HostGate {
    closed: AtomicBool,
    /// Held shared by each call into the host, and exclusively by `close`
    /// to wait for them.
    calls: RwLock<()>,
}

impl HostGate {
    /// Runs `f`, a call into the host, unless the gate is closed.
    pub fn call(&self, f: impl FnOnce()) {
        let nested = IN_HOST.with(|d| d.get()) > 0;
        // A call from inside a callback holds the lock already: taking it
        // again could wait behind a `close` that waits for this thread.
        let _held = (!nested).then(|| self.calls.read().unwrap_or_else(|e| e.into_inner()));
        if self.closed.load(Ordering::Acquire) {
            return;
        }
        IN_HOST.with(|d| d.set(d.get() + 1));
        let _depth = Leave;
        f();
    }

    /// Lets no call into the host start, and waits for those running on
    /// other threads, up to `RELEASE_WAIT` (a callback that runs on is
    /// the host's own, begun before its release). From inside a callback,
    /// which cannot wait for itself, the others are not waited for either.
    pub fn close(&self) {
        self.closed.store(true, Ordering::Release);
        if IN_HOST.with(|d| d.get()) > 0 {
            return;
        }
        let until = std::time::Instant::now() + RELEASE_WAIT;
        while self.calls.try_write().is_err() && std::time::Instant::now() < until {
            std::thread::sleep(Duration::from_millis(1));
        }
    }
}

/// Leaves a call into the host, however it ends.
struct Leave;

impl Drop for Leave {
    fn drop(&mut self) {
        IN_HOST.with(|d| d.set(d.get().saturating_sub(1)));
    }
}

/// Teardown threads that may still run.
static TEARDOWNS: Mutex<Vec<JoinHandle<()>>> = Mutex::new(Vec::new());

/// Drops `device` on a thread of its own, waiting for it up to
/// `RELEASE_WAIT`, and not at all on a thread of the device's own (a
/// completion callback releasing it: the teardown waits for that thread).
pub fn teardown<T: Send + 'static>(device: T) {
    let (done, finished) = channel::<()>();
    let spawned = std::thread::Builder::new()
        .name("caveray-teardown".into())
        .spawn(move || {
            drop(device);
            let _ = done.send(());
        });
    match spawned {
        Ok(thread) => {
            let ours = std::thread::current()
                .name()
                .is_some_and(|n| n.starts_with("caveray-"));
            let mut pending = TEARDOWNS.lock().unwrap_or_else(|e| e.into_inner());
            pending.retain(|t| !t.is_finished());
            pending.push(thread);
            drop(pending);
            if !ours {
                let _ = finished.recv_timeout(RELEASE_WAIT);
            }
        }
        // No thread to hand it to: it is torn down here, waiting for all.
        Err(e) => drop(e),
    }
}

/// Waits for every teardown still running: the library's code must stay
/// loaded until they are done.
pub fn finish_teardowns() {
    let pending = std::mem::take(&mut *TEARDOWNS.lock().unwrap_or_else(|e| e.into_inner()));
    let me = std::thread::current().id();
    for thread in pending {
        if thread.thread().id() != me {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    #[test]
    fn a_closed_gate_lets_no_call_through_and_waits_for_those_running() {
        let gate = Arc::new(HostGate::default());
        let (entered, inside) = channel();
        let (leave, left) = channel::<()>();
        let running = {
            let gate = Arc::clone(&gate);
            std::thread::spawn(move || {
                gate.call(|| {
                    entered.send(()).unwrap();
                    left.recv().unwrap();
                })
            })
        };
        inside.recv().unwrap();
        let closing = {
            let gate = Arc::clone(&gate);
            std::thread::spawn(move || gate.close())
        };
        std::thread::sleep(Duration::from_millis(20));
        assert!(!closing.is_finished(), "close waits for the running call");
        leave.send(()).unwrap();
        running.join().unwrap();
        closing.join().unwrap();
        let mut called = false;
        gate.call(|| called = true);
        assert!(!called);
    }

    #[test]
    fn a_callback_may_close_its_own_gate_and_call_again() {
        let gate = HostGate::default();
        let mut inner = false;
        gate.call(|| {
            gate.close();
            gate.call(|| inner = true);
        });
        assert!(!inner, "closed from inside: nothing more gets through");
    }

    #[test]
    fn a_teardown_that_takes_long_goes_on_in_the_background() {
        struct Slow(Arc<AtomicBool>);
        impl Drop for Slow {
            fn drop(&mut self) {
                std::thread::sleep(RELEASE_WAIT * 3);
                self.0.store(true, Ordering::Release);
            }
        }
        let dropped = Arc::new(AtomicBool::new(false));
        teardown(Slow(Arc::clone(&dropped)));
        assert!(
            !dropped.load(Ordering::Acquire),
            "the release returned first"
        );
        finish_teardowns();
        assert!(dropped.load(Ordering::Acquire));
    }
}
