//! A global allocator that starts every large block at its own offset in a page.
//!
//! The system allocator maps each large block (a column of a million points or of the grid's
//! nodes) afresh and returns it at the same offset in a page, so element `i` of every column
//! sits at the same address bits 0–11. Particle-to-grid stores node `i`'s momentum and then
//! loads its force, two columns of the same stride: the load matches the store in those bits,
//! and on the AMD Zen 3 cores measured here whether the processor then takes it for a
//! dependent load depends also on higher address bits, that is on where the run's address
//! layout put the two columns. Some layouts made particle-to-grid several times slower for a
//! whole run (the measurements are in docs/performance.md, "Figures behind the code").
//!
//! [`Coloured`] gives each large block its own "colour": it takes a block a page and a word
//! longer from the system and starts the large block in it at a chosen cache line of a page,
//! the next colour in turn, so columns allocated together never share their offset in a page.
//! This is jemalloc's cache-oblivious placement, made deterministic: colours go in allocation
//! order, and a block's offset in a page is its colour wherever the system put the block.
//!
//! Install it in a binary with
//! `#[global_allocator] static ALLOCATOR: kdmpm::infra::alloc::Coloured = kdmpm::infra::alloc::Coloured;`.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Blocks of at least this many bytes are coloured (glibc maps blocks from 128 KiB up).
pub const LARGE: usize = 128 * 1024;

/// Bytes in a page: the span over which colours differ.
pub const PAGE: usize = 4096;

/// Bytes in a cache line: the unit of a colour, and the largest alignment a coloured block
/// keeps (more strictly aligned requests are passed through uncoloured).
pub const LINE: usize = 64;

/// Colours: the lines of a page.
const COLOURS: usize = PAGE / LINE;

/// Step between the colours of consecutive blocks, in lines: odd, so coprime to
/// [`COLOURS`] and 64 blocks in a row all get different colours, and far apart for
/// neighbours in that order (the columns of one archetype are allocated one after another).
const STRIDE: usize = 17;

/// Bytes an outer block has beyond its block: enough to reach any offset in a page with a
/// word to spare before the block, for the header.
const SLACK: usize = PAGE + size_of::<usize>();

/// Number of coloured blocks handed out so far (orders the colours).
static NEXT: AtomicUsize = AtomicUsize::new(0);

/// The system allocator with large blocks coloured (see the module documentation).
#[derive(Clone, Copy, Debug, Default)]
pub struct Coloured;

impl Coloured {
    /// Whether a block of `layout` is coloured.
    fn colours(layout: Layout) -> bool {
        layout.size() >= LARGE && layout.align() <= LINE
    }

    /// The layout asked of the system allocator for a coloured block of `layout`: [`SLACK`]
    /// longer and aligned to a word, so that the system takes its plain `malloc`/`calloc`
    /// path, whose zeroed blocks stay unmapped until written. `None` when the size overflows.
    fn outer(layout: Layout) -> Option<Layout> {
        let size = layout.size().checked_add(SLACK)?;
        Layout::from_size_align(size, align_of::<usize>()).ok()
    }

    /// Offset in a page of the next coloured block: a multiple of [`LINE`].
    fn next_colour() -> usize {
        let k = NEXT.fetch_add(1, Ordering::Relaxed);
        (k % COLOURS) * STRIDE % COLOURS * LINE
    }

    /// Puts a block of colour `colour` into `outer` (null stays null) and records where
    /// `outer` starts in the word just before the block.
    ///
    /// # Safety
    /// `outer` is null or the start of a block of `Self::outer` of the block's layout, and
    /// `colour` came from [`Coloured::next_colour`].
    unsafe fn place(outer: *mut u8, colour: usize) -> *mut u8 {
        if outer.is_null() {
            return outer;
        }
        let word = size_of::<usize>();
        let mut offset = colour.wrapping_sub(outer as usize) % PAGE;
        if offset < word {
            offset += PAGE;
        }
        // SAFETY: `offset` is at least a word and below `SLACK`, so the block and the word
        // before it lie inside the outer block. The block starts at `colour` in a page, a
        // multiple of 64 bytes, so it is aligned to 64 (its own alignment is at most that);
        // `outer` is aligned to a word, and so is `offset`, so the header word is aligned.
        unsafe {
            let block = outer.add(offset);
            block.cast::<usize>().sub(1).write(outer as usize);
            block
        }
    }

    /// A block of `layout` from `system` (the system's `alloc` or `alloc_zeroed`): as the
    /// system gives it when small or over-aligned, else coloured inside an outer block.
    ///
    /// # Safety
    /// `layout` has a non-zero size, and `system` is safe to call with any such layout.
    unsafe fn take(layout: Layout, system: impl FnOnce(Layout) -> *mut u8) -> *mut u8 {
        if !Self::colours(layout) {
            return system(layout);
        }
        let Some(outer) = Self::outer(layout) else {
            return std::ptr::null_mut();
        };
        // SAFETY: `system` returns null or a block of `outer`, as `place` asks.
        unsafe { Self::place(system(outer), Self::next_colour()) }
    }

    /// Start of the outer block of a coloured `block`.
    ///
    /// # Safety
    /// `block` was returned by [`Coloured::place`].
    unsafe fn outer_of(block: *mut u8) -> *mut u8 {
        // SAFETY: `place` wrote the outer block's address there.
        unsafe { block.cast::<usize>().sub(1).read() as *mut u8 }
    }
}

// SAFETY: every block handed out lies inside a block of the system allocator, of the size
// asked and aligned to a line at least (see `place`), and is given back to it with the outer
// layout it was taken with: coloured or not is decided by the layout alone, which the caller
// repeats on `dealloc`.
unsafe impl GlobalAlloc for Coloured {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: forwarded contract.
        unsafe { Self::take(layout, |l| System.alloc(l)) }
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        // The system's zeroed block keeps its untouched pages unmapped (calloc of a fresh
        // mapping); only the header's page is written.
        // SAFETY: forwarded contract.
        unsafe { Self::take(layout, |l| System.alloc_zeroed(l)) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `take` with this layout, which coloured it exactly when
        // `colours` and `outer` allow it now.
        unsafe {
            match Self::outer(layout) {
                Some(outer) if Self::colours(layout) => System.dealloc(Self::outer_of(ptr), outer),
                _ => System.dealloc(ptr, layout),
            }
        }
    }

    // `realloc` is the trait's: a new block, a copy and a free, each through the methods
    // above, so a block that grows past `LARGE` is coloured and one that shrinks below it
    // is not. Columns are reserved once at set-up, so the copy is rare.
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A coloured block: its offset in a page, after checking it can be written throughout.
    fn page_offset_of_a_block(size: usize, align: usize) -> usize {
        let layout = Layout::from_size_align(size, align).unwrap();
        unsafe {
            let p = Coloured.alloc(layout);
            assert!(!p.is_null());
            assert_eq!(p as usize % align, 0, "alignment {align} kept");
            std::ptr::write_bytes(p, 0xAB, size);
            let sum: u64 = (0..size).step_by(4093).map(|i| u64::from(*p.add(i))).sum();
            assert_eq!(sum, 0xAB * size.div_ceil(4093) as u64);
            Coloured.dealloc(p, layout);
            p as usize % PAGE
        }
    }

    #[test]
    fn consecutive_large_blocks_start_at_different_offsets_in_a_page_and_keep_their_alignment() {
        for align in [8, 16, 32, 64] {
            // Other tests allocate at the same time, so only most pairs are consecutive.
            let offsets: Vec<usize> = (0..64)
                .map(|_| page_offset_of_a_block(3 * LARGE + 24, align))
                .collect();
            let distinct = offsets.windows(2).filter(|w| w[0] != w[1]).count();
            assert!(distinct >= 56, "{align}: {offsets:?}");
        }
        // More strictly aligned blocks are the system's, uncoloured but aligned.
        page_offset_of_a_block(LARGE, 4096);
        // Small blocks are the system's.
        page_offset_of_a_block(LARGE - 1, 8);
    }

    #[test]
    fn a_zeroed_coloured_block_reads_zero_and_a_grown_one_keeps_its_contents() {
        unsafe {
            let small = Layout::from_size_align(1000, 8).unwrap();
            let p = Coloured.alloc_zeroed(Layout::from_size_align(2 * LARGE, 8).unwrap());
            assert!((0..2 * LARGE).all(|i| *p.add(i) == 0));
            Coloured.dealloc(p, Layout::from_size_align(2 * LARGE, 8).unwrap());
            // Small → coloured → larger coloured → small again, the prefix kept each time.
            let mut p = Coloured.alloc(small);
            for i in 0..1000 {
                *p.add(i) = (i % 251) as u8;
            }
            let mut layout = small;
            for size in [LARGE + 8, 5 * LARGE, 512] {
                p = Coloured.realloc(p, layout, size);
                layout = Layout::from_size_align(size, 8).unwrap();
                assert!((0..512).all(|i| *p.add(i) == (i % 251) as u8), "to {size}");
            }
            Coloured.dealloc(p, layout);
        }
    }
}
