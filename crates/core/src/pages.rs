//! Large working arrays on huge pages.
//!
//! The 2-D transforms walk their row-transformed data by columns, one 64-byte line per row,
//! rows `16 (n/2 + 1)` bytes apart: at 1024² a column group touches 1024 different 4 KiB
//! pages, more than the processor's first-level TLB holds. On 2 MiB pages the same walk
//! touches four. Linux gives a process transparent huge pages where it asks for them
//! (`madvise(MADV_HUGEPAGE)`, the default `madvise` mode of
//! `/sys/kernel/mm/transparent_hugepage/enabled`), as numpy does for every array of 4 MiB
//! or more, and so for the arrays FFTW works on in `make bench-fft`. In interleaved runs
//! the 2048² pair took 0.955 of its time on 4 KiB pages, the 1024² pair 0.93 or the same
//! depending on the VM's state (docs/BENCHMARKS.md).
//!
//! Only where the memory is placed changes: values, results and the bytes allocated are
//! the same (the kernel may round the resident size of a huge-page region up to 2 MiB).
//! Elsewhere than Linux, or if the kernel refuses, the advice is a no-op.

/// Size of a transparent huge page on x86-64 and aarch64 Linux.
const HUGE_PAGE: usize = 2 << 20;

/// A vector of `len` copies of `value` whose storage, if it spans whole 2 MiB pages, is
/// advised onto huge pages before its first write (only the 2 MiB-aligned interior: the
/// ends share pages with other allocations).
pub fn filled<T: Clone>(len: usize, value: T) -> Vec<T> {
    let mut v: Vec<T> = Vec::with_capacity(len);
    advise_huge_pages(v.as_mut_ptr() as usize, len * std::mem::size_of::<T>());
    v.resize(len, value);
    v
}

/// Ask for huge pages on the whole 2 MiB pages within `bytes` from address `start`.
fn advise_huge_pages(start: usize, bytes: usize) {
    let first = start.next_multiple_of(HUGE_PAGE);
    let end = (start + bytes) / HUGE_PAGE * HUGE_PAGE;
    if end <= first {
        return;
    }
    #[cfg(target_os = "linux")]
    // SAFETY: madvise only gives advice about pages of this process's own allocation
    // (`first .. end` lies within it); MADV_HUGEPAGE changes no contents.
    unsafe {
        libc::madvise(first as *mut libc::c_void, end - first, libc::MADV_HUGEPAGE);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The values are those asked for, small or large.
    #[test]
    fn filled_holds_len_copies_of_the_value() {
        for len in [0, 1, 1000, 3 << 20] {
            let v = filled(len, 2.5f64);
            assert_eq!(v.len(), len);
            assert!(v.iter().all(|&x| x == 2.5));
        }
    }

    /// On Linux with transparent huge pages available (`always` or `madvise`), the mapping
    /// holding a 16 MiB array is eligible for them (`THPeligible: 1` in /proc/self/smaps),
    /// which under `madvise` only the advice makes it.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_large_array_is_eligible_for_huge_pages() {
        let mode = std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled")
            .unwrap_or_default();
        if mode.is_empty() || mode.contains("[never]") {
            assert!(
                std::env::var("CI").is_err(),
                "CI machines must offer transparent huge pages (mode: {mode:?})"
            );
            return;
        }
        let v = filled(2 << 20, 1.0f64);
        let address = v.as_ptr() as usize + (8 << 20);
        let smaps = std::fs::read_to_string("/proc/self/smaps").unwrap();
        let mut inside = false;
        let mut eligible = None;
        for line in smaps.lines() {
            if let Some((range, _)) = line.split_once(' ') {
                if let Some((lo, hi)) = range.split_once('-') {
                    if let (Ok(lo), Ok(hi)) =
                        (usize::from_str_radix(lo, 16), usize::from_str_radix(hi, 16))
                    {
                        inside = lo <= address && address < hi;
                        continue;
                    }
                }
            }
            if inside {
                if let Some(flag) = line.strip_prefix("THPeligible:") {
                    eligible = Some(flag.trim() == "1");
                }
            }
        }
        assert_eq!(eligible, Some(true), "THP mode {mode:?}");
        assert_eq!(v[1 << 20], 1.0);
    }
}
