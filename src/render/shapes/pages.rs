//! Large build arrays in 2 MiB pages. The kernel here gives transparent
//! huge pages only where asked (`madvise`), and a million triangles'
//! build writes about 100 MB of fresh memory: in 4 KiB pages that is
//! 25 000 page faults, a fifth of the build's time.

use std::mem::MaybeUninit;

const HUGE: usize = 2 << 20;

/// Asks for `memory`, not yet written, to be backed by huge pages where
/// it spans them whole. Only advice: nothing changes where it is refused.
pub fn ask_huge<T>(memory: &mut [MaybeUninit<T>]) {
    let bytes = std::mem::size_of_val(memory);
    if bytes < 2 * HUGE {
        return;
    }
    let start = (memory.as_mut_ptr() as usize).next_multiple_of(HUGE);
    let end = (memory.as_mut_ptr() as usize + bytes) / HUGE * HUGE;
    if end > start {
        #[cfg(target_os = "linux")]
        // SAFETY: the range lies within `memory`, which this call borrows
        // mutably; the advice changes no byte of it.
        unsafe {
            libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
        }
    }
}
