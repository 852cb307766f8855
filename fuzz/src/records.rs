//! The record format of the `line_frames` and `mailbox` inputs.
//!
//! After the target's header byte(s), an input is a sequence of records:
//! one tag byte, a little-endian `u16` body length, then the body. A
//! length that runs past the end of the input takes what is left, so every
//! byte string is a valid input. Seeds are written with [`push`].

/// Iterator over the records of an input.
#[derive(Debug, Clone)]
pub struct Records<'a> {
    rest: &'a [u8],
}

impl<'a> Records<'a> {
    /// The records of `data` (the input after its header).
    pub fn new(data: &'a [u8]) -> Self {
        Records { rest: data }
    }
}

impl<'a> Iterator for Records<'a> {
    /// (tag, body).
    type Item = (u8, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        let (&tag, rest) = self.rest.split_first()?;
        let (len, rest) = match rest {
            [a, b, tail @ ..] => (usize::from(u16::from_le_bytes([*a, *b])), tail),
            _ => (0, &[][..]),
        };
        let (body, tail) = rest.split_at(len.min(rest.len()));
        self.rest = tail;
        Some((tag, body))
    }
}

/// Appends a record (bodies over 65535 bytes are cut).
pub fn push(out: &mut Vec<u8>, tag: u8, body: &[u8]) {
    let body = &body[..body.len().min(usize::from(u16::MAX))];
    out.push(tag);
    out.extend_from_slice(&(body.len() as u16).to_le_bytes());
    out.extend_from_slice(body);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_round_trip_and_truncate() {
        let mut v = vec![];
        push(&mut v, 1, b"abc");
        push(&mut v, 2, b"");
        v.extend_from_slice(&[3, 10, 0, b'x']);
        let r: Vec<_> = Records::new(&v).collect();
        assert_eq!(r, vec![(1, &b"abc"[..]), (2, &b""[..]), (3, &b"x"[..])]);
        assert_eq!(Records::new(&[7]).collect::<Vec<_>>(), vec![(7, &b""[..])]);
    }
}
