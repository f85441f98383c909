//! The generated crate never allocates: decoding, encoding and stream decoding of the benches'
//! mixed streams and captures, counted by a global allocator that counts the allocations of
//! the thread it runs on (so the test harness's own threads do not disturb the count).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use busspec_benches::mixed::{capture, Mixed, Proto};
use busspec_benches::{
    decode_all, encode_all, jobs, messages, stream_sd, stream_ub2, Contender, Generated, Interp,
    Sd, Ub2,
};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // `try_with`: the thread-local may already be gone while a thread shuts down.
        let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Heap allocations `f` makes on this thread, and its result.
fn allocations<T>(f: impl FnOnce() -> T) -> (u64, T) {
    let before = ALLOCATIONS.with(Cell::get);
    let out = f();
    (ALLOCATIONS.with(Cell::get) - before, out)
}

/// Decodes and re-encodes the whole mixed stream with `c`; returns the allocations of each.
fn count<C: Contender>(c: &C, mixed: &Mixed) -> (u64, u64) {
    let jobs = jobs(c, mixed);
    let msgs = messages(c, mixed);
    let mut out = vec![0u8; mixed.bytes.len()];
    let (dec, ok) = allocations(|| decode_all(c, &mixed.bytes, &jobs));
    assert_eq!(ok, mixed.entries.len());
    let (enc, n) = allocations(|| encode_all(c, &msgs, &mut out));
    assert_eq!(n, Some(mixed.bytes.len()));
    (dec, enc)
}

#[test]
fn the_counter_counts_what_allocates() {
    let (n, v) = allocations(|| vec![1u8; 100]);
    assert_eq!((n, v.len()), (1, 100));
    // The interpreter allocates while decoding, so the same measurement as below sees it.
    let p = Proto::Sd.spec();
    let mixed = Mixed::from_spec(Proto::Sd, &p);
    let (dec, enc) = count(&Interp(&p), &mixed);
    assert!(dec > 0 && enc > 0, "{dec} {enc}");
}

#[test]
fn generated_decode_and_encode_never_allocate() {
    let ub2 = Mixed::new(Proto::Ub2);
    assert_eq!(count(&Generated::<Ub2>::default(), &ub2), (0, 0), "ub2");
    let sd = Mixed::new(Proto::Sd);
    assert_eq!(count(&Generated::<Sd>::default(), &sd), (0, 0), "sd");
}

#[test]
fn the_generated_stream_decoder_never_allocates() {
    for proto in Proto::ALL {
        let cap = capture(&proto.spec(), 64 << 10);
        let (n, found) = allocations(|| match proto {
            Proto::Ub2 => stream_ub2(&cap),
            Proto::Sd => stream_sd(&cap),
        });
        assert_eq!(n, 0, "{}", proto.name());
        assert!(found.frames > 1000, "{}: {found:?}", proto.name());
    }
}
