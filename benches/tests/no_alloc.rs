//! The generated crate never allocates: decoding, encoding and stream decoding of the benches'
//! mixed streams and captures, counted by a global allocator that counts the allocations of
//! the thread it runs on (so the test harness's own threads do not disturb the count).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use busspec_benches::mixed::{capture, Mixed, Proto};
use busspec_benches::{
    decode_all, encode_all, jobs, messages, stream_generated, Contender, Generated, Interp,
};
use busspec_protocols::sd::Sd;
use busspec_protocols::ub2::Ub2;
use busspec_protocols::Protocol;

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

/// `P`'s generated decoder and encoder over its mixed stream: no allocation.
fn codec_never_allocates<P: Protocol>() {
    let mixed = Mixed::new(Proto::of::<P>());
    assert_eq!(
        count(&Generated::<P>::default(), &mixed),
        (0, 0),
        "{}",
        P::NAME
    );
}

#[test]
fn generated_decode_and_encode_never_allocate() {
    codec_never_allocates::<Ub2>();
    codec_never_allocates::<Sd>();
}

/// `P`'s generated stream decoder over 64 KiB of its capture: no allocation.
fn stream_never_allocates<P: Protocol>() {
    let proto = Proto::of::<P>();
    let cap = capture(&proto.spec(), 64 << 10);
    let (n, found) = allocations(|| stream_generated::<P>(&cap));
    assert_eq!(n, 0, "{}", P::NAME);
    assert!(found.frames > 1000, "{}: {found:?}", P::NAME);
}

#[test]
fn the_generated_stream_decoder_never_allocates() {
    stream_never_allocates::<Ub2>();
    stream_never_allocates::<Sd>();
}
