//! A response body: a short text, or a file read in chunks (so a large file never sits whole in memory).

use std::io;
use std::pin::Pin;
use std::task::{Context, Poll, ready};

use hyper::body::{Body, Bytes, Frame, SizeHint};
use tokio::io::{AsyncRead, ReadBuf};

/// Bytes read from a file per chunk.
pub const CHUNK: usize = 64 * 1024;

/// What a response carries.
pub enum Payload {
    /// A short text (or nothing once sent).
    Text(Option<Bytes>),
    /// `left` more bytes of `file`.
    File {
        /// The open file.
        file: tokio::fs::File,
        /// Bytes still to send.
        left: u64,
        /// The read buffer.
        buf: Box<[u8]>,
    },
}

impl Payload {
    /// A text body.
    pub fn text(s: impl Into<String>) -> Payload {
        Payload::Text(Some(Bytes::from(s.into())))
    }

    /// The whole of `file`, `len` bytes long.
    pub fn file(file: tokio::fs::File, len: u64) -> Payload {
        Payload::File { file, left: len, buf: vec![0; CHUNK].into_boxed_slice() }
    }
}

impl Body for Payload {
    type Data = Bytes;
    type Error = io::Error;

    fn poll_frame(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<io::Result<Frame<Bytes>>>> {
        match self.get_mut() {
            Payload::Text(text) => Poll::Ready(text.take().map(|b| Ok(Frame::data(b)))),
            Payload::File { file, left, buf } => {
                if *left == 0 {
                    return Poll::Ready(None);
                }
                let want = buf.len().min(usize::try_from(*left).unwrap_or(usize::MAX));
                let mut read = ReadBuf::new(&mut buf[..want]);
                ready!(Pin::new(file).poll_read(cx, &mut read))?;
                let got = read.filled();
                if got.is_empty() {
                    return Poll::Ready(Some(Err(io::Error::new(
                        io::ErrorKind::UnexpectedEof,
                        "the file got shorter while it was being sent",
                    ))));
                }
                *left -= got.len() as u64;
                Poll::Ready(Some(Ok(Frame::data(Bytes::copy_from_slice(got)))))
            }
        }
    }

    fn is_end_stream(&self) -> bool {
        match self {
            Payload::Text(t) => t.is_none(),
            Payload::File { left, .. } => *left == 0,
        }
    }

    fn size_hint(&self) -> SizeHint {
        match self {
            Payload::Text(t) => SizeHint::with_exact(t.as_ref().map_or(0, |b| b.len() as u64)),
            Payload::File { left, .. } => SizeHint::with_exact(*left),
        }
    }
}
