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

#[cfg(test)]
mod tests {
    // Host check (the crate itself is target-only): `rustc --edition 2021 --test src/ring.rs`.
    use super::Ring;

    #[test]
    fn fifo_order_capacity_and_wrap() {
        let r: Ring<8> = Ring::new();
        assert!(r.is_empty());
        for round in 0..1000u32 {
            let n = (round % 9) as u8;
            for i in 0..n {
                assert!(r.push(i.wrapping_add(round as u8)));
            }
            assert_eq!(r.len(), u32::from(n));
            for i in 0..n {
                assert_eq!(r.peek(), Some(i.wrapping_add(round as u8)));
                assert_eq!(r.pop(), Some(i.wrapping_add(round as u8)));
            }
            assert_eq!(r.pop(), None);
        }
        for i in 0..8 {
            assert!(r.push(i));
        }
        assert!(!r.push(99), "a full ring refuses a byte");
        assert_eq!(r.pop(), Some(0));
        assert!(r.push(8));
        for i in 1..=8 {
            assert_eq!(r.pop(), Some(i));
        }
    }

    #[test]
    fn counters_wrap_at_u32() {
        let r: Ring<4> = Ring::new();
        r.head
            .store(u32::MAX - 1, core::sync::atomic::Ordering::Relaxed);
        r.tail
            .store(u32::MAX - 1, core::sync::atomic::Ordering::Relaxed);
        for i in 0..4 {
            assert!(r.push(i));
        }
        assert!(!r.push(4));
        for i in 0..4 {
            assert_eq!(r.pop(), Some(i));
        }
        assert!(r.is_empty());
    }

    #[test]
    fn two_threads_lose_and_reorder_nothing() {
        extern crate std;
        static R: Ring<16> = Ring::new();
        const COUNT: u32 = 200_000;
        let producer = std::thread::spawn(|| {
            let mut i = 0u32;
            while i < COUNT {
                if R.push(i as u8) {
                    i += 1;
                }
            }
        });
        let mut expect = 0u32;
        while expect < COUNT {
            if let Some(b) = R.pop() {
                assert_eq!(b, expect as u8);
                expect += 1;
            }
        }
        producer.join().unwrap();
        assert!(R.is_empty());
    }
}
