//! Storage that is read and written cell by cell (grids, pictures' pixel masks).
//!
//! `vec![0; n]` asks the allocator for zeroed memory, and a large block comes straight from the
//! kernel: pages that read as the kernel's one shared zero page until written. A cell read before
//! it is written (`cell += 1`, `bits |= bit`) first maps that shared page; the write that follows
//! is a copy-on-write fault, and replacing a mapping means flushing it from every core that runs
//! one of the process's threads: an interrupt to each. A run's grid and its map picture did that
//! once per page of their storage, each time interrupting the simulation on the other core.
//! [`written_zeros`] writes its zeros instead, so each page is faulted in once, writable, with
//! nothing to flush (the occupancy grid, which copies its old rows into new storage as it grows,
//! writes its rows and zeros in one pass to the same end).

/// `n` zeros (`T::default()`), every page written now (see the module's notes).
pub fn written_zeros<T: Copy + Default>(n: usize) -> Vec<T> {
    let mut cells = Vec::with_capacity(n);
    cells.resize(n, T::default());
    cells
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_zeros_are_zeros_of_the_length_asked() {
        for n in [0, 1, 4095, 1 << 20] {
            let cells: Vec<f32> = written_zeros(n);
            assert_eq!(cells.len(), n);
            assert!(cells.iter().all(|&c| c.to_bits() == 0));
            let words: Vec<u64> = written_zeros(n);
            assert!(words.iter().all(|&w| w == 0));
        }
    }
}
