//! The machine's memory bandwidth, as John McCalpin's STREAM measures it: copy, scale, add
//! and triad over three arrays of f64 far larger than the caches, on 1 and 2 threads, best
//! of ten passes each, bytes counted as STREAM counts them (a write's read for ownership
//! left out). It is the bound the byte budget of docs/performance.md sets a step against.
//!
//! `cargo bench -p kdmpm-bench --bench stream [-- --len N]` (N elements an array, default
//! 2^25: 256 MiB an array).

use rayon::prelude::*;
use std::hint::black_box;
use std::time::Instant;

const CHUNK: usize = 1 << 16;

fn best_of(passes: usize, mut f: impl FnMut()) -> f64 {
    (0..passes)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let len = args
        .iter()
        .position(|a| a == "--len")
        .and_then(|i| args.get(i + 1))
        .map_or(1 << 25, |v| v.parse().expect("--len takes a number"));
    let mb = |bytes: usize, s: f64| bytes as f64 / s / 1e9;
    println!("arrays of {len} f64 ({} MiB each)", (len * 8) >> 20);
    println!(
        "{:>8} {:>10} {:>10} {:>10} {:>10}",
        "threads", "copy", "scale", "add", "triad"
    );
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        pool.install(|| {
            // Each thread first touches the pages it streams later.
            let make = |v: f64| {
                let mut a = Vec::with_capacity(len);
                a.spare_capacity_mut()
                    .par_chunks_mut(CHUNK)
                    .for_each(|c| c.iter_mut().for_each(|x| _ = x.write(v)));
                // SAFETY: every element up to `len` was written just above.
                unsafe { a.set_len(len) };
                a
            };
            let (mut a, mut b, mut c) = (make(1.0), make(2.0), make(0.0));
            let s = black_box(3.0);
            let copy = best_of(10, || {
                c.par_chunks_mut(CHUNK)
                    .zip(a.par_chunks(CHUNK))
                    .for_each(|(c, a)| c.copy_from_slice(a));
                black_box(&c);
            });
            let scale = best_of(10, || {
                b.par_chunks_mut(CHUNK)
                    .zip(c.par_chunks(CHUNK))
                    .for_each(|(b, c)| b.iter_mut().zip(c).for_each(|(b, c)| *b = s * c));
                black_box(&b);
            });
            let add = best_of(10, || {
                c.par_chunks_mut(CHUNK)
                    .zip(a.par_chunks(CHUNK).zip(b.par_chunks(CHUNK)))
                    .for_each(|(c, (a, b))| {
                        c.iter_mut()
                            .zip(a.iter().zip(b))
                            .for_each(|(c, (a, b))| *c = a + b)
                    });
                black_box(&c);
            });
            let triad = best_of(10, || {
                a.par_chunks_mut(CHUNK)
                    .zip(b.par_chunks(CHUNK).zip(c.par_chunks(CHUNK)))
                    .for_each(|(a, (b, c))| {
                        a.iter_mut()
                            .zip(b.iter().zip(c))
                            .for_each(|(a, (b, c))| *a = b + s * c)
                    });
                black_box(&a);
            });
            println!(
                "{threads:>8} {:>10.1} {:>10.1} {:>10.1} {:>10.1}   GB/s",
                mb(16 * len, copy),
                mb(16 * len, scale),
                mb(24 * len, add),
                mb(24 * len, triad)
            );
        });
    }
}
