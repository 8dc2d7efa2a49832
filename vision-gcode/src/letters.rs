//! The word letters and their slots in the per-line arrays: `A`–`Z`, then `$` and LinuxCNC's
//! polar `@` and `^`. A leaf: the parser and the word reader both use it.

/// Slot of `$` in the letter arrays (after `A`–`Z`), then LinuxCNC's polar `@` and `^`.
const DOLLAR: usize = 26;
const AT: usize = 27;
const CARET: usize = 28;
pub(crate) const SLOTS: usize = 29;

/// The slots by ASCII code: a table, not a `match`, as this runs for every word.
#[expect(clippy::cast_possible_truncation, reason = "the slots are below 29")]
const SLOT_OF: [u8; 128] = {
    let mut table = [0u8; 128];
    let mut c = b'A';
    while c <= b'Z' {
        table[c as usize] = c - b'A';
        c += 1;
    }
    table[b'$' as usize] = DOLLAR as u8;
    table[b'@' as usize] = AT as u8;
    table[b'^' as usize] = CARET as u8;
    table
};

/// The slot of an upper-case letter, `$`, `@` or `^` (the parser passes no other byte).
#[inline]
pub(crate) fn slot(letter: u8) -> usize {
    usize::from(SLOT_OF[usize::from(letter & 0x7f)])
}

/// The letter of a slot.
pub(crate) fn letter_of(slot: usize) -> char {
    match slot {
        DOLLAR => '$',
        AT => '@',
        CARET => '^',
        _ => char::from(b'A' + u8::try_from(slot).unwrap_or(0)),
    }
}
