//! A connection that fails with `TimedOut` once no byte has moved in either direction for a set time: the
//! read and write timeout of every connection, so a client that stops reading (or sending) only holds its
//! own connection, and only that long.

use std::future::Future;
use std::io;
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::time::{Instant, Sleep};

/// A stream with an inactivity timeout.
pub struct Inactivity<S> {
    inner: S,
    limit: Duration,
    timer: Pin<Box<Sleep>>,
    armed: bool,
}

impl<S> Inactivity<S> {
    /// `inner`, failing after `limit` without progress.
    pub fn new(inner: S, limit: Duration) -> Inactivity<S> {
        Inactivity { inner, limit, timer: Box::pin(tokio::time::sleep(limit)), armed: false }
    }

    /// Called when the stream made progress.
    fn progressed<T>(&mut self, ready: T) -> Poll<T> {
        self.armed = false;
        Poll::Ready(ready)
    }

    /// Called when the stream would wait: starts the clock if it is not running, and fails once it ran out.
    fn waiting<T>(&mut self, cx: &mut Context<'_>) -> Poll<io::Result<T>> {
        if !self.armed {
            self.timer.as_mut().reset(Instant::now() + self.limit);
            self.armed = true;
        }
        match self.timer.as_mut().poll(cx) {
            Poll::Ready(()) => Poll::Ready(Err(io::Error::new(
                io::ErrorKind::TimedOut,
                format!("no data moved for {} s", self.limit.as_secs_f64()),
            ))),
            Poll::Pending => Poll::Pending,
        }
    }
}

impl<S: AsyncRead + Unpin> AsyncRead for Inactivity<S> {
    fn poll_read(self: Pin<&mut Self>, cx: &mut Context<'_>, buf: &mut ReadBuf<'_>) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        match Pin::new(&mut this.inner).poll_read(cx, buf) {
            Poll::Ready(r) => this.progressed(r),
            Poll::Pending => this.waiting(cx),
        }
    }
}

impl<S: AsyncWrite + Unpin> AsyncWrite for Inactivity<S> {
    fn poll_write(self: Pin<&mut Self>, cx: &mut Context<'_>, data: &[u8]) -> Poll<io::Result<usize>> {
        let this = self.get_mut();
        match Pin::new(&mut this.inner).poll_write(cx, data) {
            Poll::Ready(r) => this.progressed(r),
            Poll::Pending => this.waiting(cx),
        }
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        match Pin::new(&mut this.inner).poll_flush(cx) {
            Poll::Ready(r) => this.progressed(r),
            Poll::Pending => this.waiting(cx),
        }
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let this = self.get_mut();
        match Pin::new(&mut this.inner).poll_shutdown(cx) {
            Poll::Ready(r) => this.progressed(r),
            Poll::Pending => this.waiting(cx),
        }
    }
}

#[cfg(test)]
mod tests {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};

    use super::*;

    fn runtime() -> tokio::runtime::Runtime {
        tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap()
    }

    #[test]
    fn a_peer_that_stops_reading_times_the_writer_out() {
        runtime().block_on(async {
            let (near, _far) = tokio::io::duplex(1024);
            let mut near = Inactivity::new(near, Duration::from_millis(200));
            let start = std::time::Instant::now();
            let err = near.write_all(&[7; 64 * 1024]).await.unwrap_err();
            assert_eq!(err.kind(), io::ErrorKind::TimedOut);
            assert!(start.elapsed() < Duration::from_secs(5));
        });
    }

    #[test]
    fn a_silent_peer_times_the_reader_out_but_a_slow_steady_one_does_not() {
        runtime().block_on(async {
            let (near, mut far) = tokio::io::duplex(1024);
            let mut near = Inactivity::new(near, Duration::from_millis(300));
            let feeder = tokio::spawn(async move {
                for _ in 0..6 {
                    tokio::time::sleep(Duration::from_millis(100)).await;
                    far.write_all(b"x").await.unwrap();
                }
                far
            });
            let mut got = [0u8; 6];
            near.read_exact(&mut got).await.unwrap();
            let _far = feeder.await.unwrap();
            let err = near.read_u8().await.unwrap_err();
            assert_eq!(err.kind(), io::ErrorKind::TimedOut);
        });
    }
}
