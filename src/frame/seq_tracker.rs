//! The frame counter unwrapped into message slots: where each message lands in the counter
//! sequence, how many frames were lost before it, or that it repeats the last one (the counter
//! rules of [`super::decoder`]'s documentation, interleaved formats included).

/// Where a message landed in the counter sequence.
pub(super) enum Placement {
    /// Not tracked (no counter, or before the first frame of an interleaved format).
    Untracked,
    Duplicate,
    /// Advanced; `missing` frames lost before it; `seq` set for frames.
    Advanced {
        missing: u64,
        seq: u64,
    },
}

/// Unwraps the counter into message slots; see the decoder's documentation ("Counter rules").
pub(super) struct SeqTracker {
    pub(super) modulus: u64,
    /// Slots per frame (1 without interleave).
    pub(super) cycle: u64,
    /// Last tracked message: (slot, counter, is_frame).
    pub(super) last: Option<(u64, u64, bool)>,
    /// Seq of the last frame, kept across a re-anchor.
    pub(super) last_seq: Option<u64>,
    /// Bytes of the last tracked message (interleaved formats): a message with the same counter
    /// and kind is a repeat only if its bytes are the same.
    pub(super) last_msg: Vec<u8>,
}

impl SeqTracker {
    /// [`SeqTracker::place`] for an interleaved message: its bytes tell a repeat (same bytes)
    /// from an advance of a whole `lcm(M, cycle)` (same counter and kind, other bytes).
    pub(super) fn observe_msg(
        &mut self,
        is_frame: bool,
        counter: u64,
        msg: &[u8],
        breaks: &mut u64,
    ) -> Placement {
        let repeat = self.last_msg == msg;
        let p = self.place(is_frame, counter, repeat, breaks);
        if !matches!(p, Placement::Duplicate) {
            self.last_msg.clear();
            self.last_msg.extend_from_slice(msg);
        }
        p
    }

    /// Places a message whose bytes are not compared: the same counter and kind is a repeat.
    pub(super) fn observe(&mut self, is_frame: bool, counter: u64, breaks: &mut u64) -> Placement {
        self.place(is_frame, counter, true, breaks)
    }

    /// `may_repeat`: an advance of 0 (a repeated message) is allowed.
    pub(super) fn place(
        &mut self,
        is_frame: bool,
        counter: u64,
        may_repeat: bool,
        breaks: &mut u64,
    ) -> Placement {
        let m = self.modulus;
        let Some((slot, c_prev, prev_is_frame)) = self.last else {
            if !is_frame {
                return Placement::Untracked;
            }
            // Anchor: the first frame (or the first after a break) keeps seq continuity.
            // Without interleave the first seq is the counter itself; with it the counter says
            // little about the frame number, so frames count from 0.
            let seq = match self.last_seq {
                None if self.cycle == 1 => counter,
                None => 0,
                Some(s) => s + 1,
            };
            self.last = Some((seq * self.cycle, counter, true));
            self.last_seq = Some(seq);
            return Placement::Advanced { missing: 0, seq };
        };
        let d = (counter + m - c_prev % m) % m;
        let mut found = None;
        // lcm(m, cycle) <= m * cycle bounds the search for a consistent advance.
        let mut a = d;
        while a <= m * self.cycle {
            let on_frame_slot = (slot + a).is_multiple_of(self.cycle);
            let ok = if a == 0 {
                may_repeat && is_frame == prev_is_frame
            } else {
                on_frame_slot == is_frame
            };
            if ok {
                found = Some(a);
                break;
            }
            a += m;
        }
        match found {
            Some(0) => Placement::Duplicate,
            Some(a) => {
                let new_slot = slot + a;
                // Frame slots strictly between the two messages.
                let missing = (new_slot - 1) / self.cycle - slot / self.cycle;
                self.last = Some((new_slot, counter, is_frame));
                let seq = new_slot / self.cycle;
                if is_frame {
                    self.last_seq = Some(seq);
                }
                Placement::Advanced { missing, seq }
            }
            None => {
                *breaks += 1;
                self.last = None;
                if is_frame {
                    self.place(true, counter, may_repeat, breaks)
                } else {
                    Placement::Untracked
                }
            }
        }
    }
}
