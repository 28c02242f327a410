//! A lock-free single-producer single-consumer byte ring for interrupt ↔ thread-mode hand-over.
//!
//! Units: bytes. `N` is a power of two (checked at compile time) and the ring holds up to `N`
//! bytes. Invariants: exactly one context calls `push` and exactly one calls `pop` (the serial
//! driver's split into `SerialIsr` and `SerialPort` guarantees it); head and tail are free-running
//! `u32` counters, so `head − tail` (wrapping) is the fill level and an index is `counter & (N−1)`.
//! No division, no indexing that can fail, no `unsafe`: the slots are `AtomicU8`, so even misuse
//! could only reorder bytes, never be undefined behaviour. Release/acquire ordering on the
//! counters publishes a slot's byte before its index.

use core::sync::atomic::{AtomicU32, AtomicU8, Ordering};

/// The ring. Build it in a `static` with `Ring::new()`.
pub struct Ring<const N: usize> {
    buf: [AtomicU8; N],
    /// Next slot to write (owned by the producer).
    head: AtomicU32,
    /// Next slot to read (owned by the consumer).
    tail: AtomicU32,
}

impl<const N: usize> Ring<N> {
    const MASK: u32 = {
        assert!(
            N.is_power_of_two() && N <= 1 << 16,
            "N must be a power of two ≤ 65536"
        );
        (N - 1) as u32
    };

    /// An empty ring.
    pub const fn new() -> Self {
        Self {
            buf: [const { AtomicU8::new(0) }; N],
            head: AtomicU32::new(0),
            tail: AtomicU32::new(0),
        }
    }

    /// Bytes waiting.
    #[inline(always)]
    pub fn len(&self) -> u32 {
        self.head
            .load(Ordering::Acquire)
            .wrapping_sub(self.tail.load(Ordering::Acquire))
    }

    /// Whether no byte is waiting.
    #[inline(always)]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Appends a byte (producer only); `false` if the ring is full.
    #[inline(always)]
    pub fn push(&self, byte: u8) -> bool {
        let head = self.head.load(Ordering::Relaxed);
        if head.wrapping_sub(self.tail.load(Ordering::Acquire)) > Self::MASK {
            return false;
        }
        if let Some(slot) = self.buf.get((head & Self::MASK) as usize) {
            slot.store(byte, Ordering::Relaxed);
        }
        self.head.store(head.wrapping_add(1), Ordering::Release);
        true
    }

    /// The oldest byte without removing it (consumer only).
    #[inline(always)]
    pub fn peek(&self) -> Option<u8> {
        let tail = self.tail.load(Ordering::Relaxed);
        if self.head.load(Ordering::Acquire) == tail {
            return None;
        }
        self.buf
            .get((tail & Self::MASK) as usize)
            .map(|slot| slot.load(Ordering::Relaxed))
    }

    /// Removes and returns the oldest byte (consumer only).
    #[inline(always)]
    pub fn pop(&self) -> Option<u8> {
        let byte = self.peek()?;
        let tail = self.tail.load(Ordering::Relaxed);
        self.tail.store(tail.wrapping_add(1), Ordering::Release);
        Some(byte)
    }
}
