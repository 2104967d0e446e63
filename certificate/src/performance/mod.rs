//! What the certificate measures in time and memory, with the machine it ran on:
//!
//! - [`timings`]: VERIFICATION.md's "Error against run time" (`verify --timings`);
//! - [`bench_table`]: criterion's timings and the targets in the READMEs (`bench-table`);
//! - [`bench_compare`]: the bar's step benches beside another commit's (`bench-compare`);
//! - [`peak_memory`]: a long run's peak resident memory (`peak-memory`).

pub mod bench_compare;
pub mod bench_table;
pub mod peak_memory;
pub mod timings;
