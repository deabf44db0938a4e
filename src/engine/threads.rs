//! Joining the engine's threads.

use std::thread::JoinHandle;

/// Joins `thread` unless it is the calling thread, which cannot wait for
/// its own end (it is running the drop or the call that asked): it ends
/// by itself once that returns.
pub fn join_unless_current(thread: JoinHandle<()>) {
    if thread.thread().id() != std::thread::current().id() {
        let _ = thread.join();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc::channel;

    #[test]
    fn a_thread_told_to_join_itself_goes_on() {
        let (tx, rx) = channel::<JoinHandle<()>>();
        let (done_tx, done_rx) = channel();
        let thread = std::thread::spawn(move || {
            // The drop of a device on its own render thread, in miniature.
            join_unless_current(rx.recv().unwrap());
            done_tx.send(()).unwrap();
        });
        let id = thread.thread().id();
        tx.send(thread).unwrap();
        done_rx.recv().unwrap();
        assert_ne!(id, std::thread::current().id());
    }
}
