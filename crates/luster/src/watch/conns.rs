//! The watch server's open connections: a slot each, up to
//! [`MAX_CONNECTIONS`]; which one gives way to a new connection (the one
//! waiting longest for a request; none while all are being answered); and
//! how many are event streams.

use std::net::{Shutdown, TcpStream};
use std::sync::{Mutex, MutexGuard};
use std::time::Instant;

/// Connections open at once (each holds a thread).
pub const MAX_CONNECTIONS: usize = 64;

/// Event streams open at once, out of [`MAX_CONNECTIONS`].
pub const MAX_STREAMS: usize = 32;

/// The open connections: which may be closed for a new one, and how many
/// are event streams.
#[derive(Default)]
pub(super) struct Conns {
    table: Mutex<Table>,
}

#[derive(Default)]
struct Table {
    next: u64,
    open: Vec<Slot>,
    streams: usize,
    closed: bool,
}

struct Slot {
    id: u64,
    /// A handle on the socket, to shut it down from another thread.
    socket: TcpStream,
    /// Since when it waits for a request (`None`: being answered).
    waiting: Option<Instant>,
}

impl Conns {
    fn lock(&self) -> MutexGuard<'_, Table> {
        // A panic while holding the lock left plain data behind: keep using it.
        self.table.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Takes `socket` on, closing the connection that has waited longest
    /// for a request when all slots are taken; `None` when none waits.
    pub(super) fn admit(&self, socket: &TcpStream) -> Option<u64> {
        let handle = socket.try_clone().ok()?;
        let mut t = self.lock();
        if t.closed {
            return None;
        }
        if t.open.len() >= MAX_CONNECTIONS {
            let oldest = (0..t.open.len())
                .filter(|&i| t.open[i].waiting.is_some())
                .min_by_key(|&i| t.open[i].waiting)?;
            let slot = t.open.swap_remove(oldest);
            // Its thread, blocked in a read, sees the end of the stream.
            let _ = slot.socket.shutdown(Shutdown::Both);
        }
        t.next += 1;
        let id = t.next;
        t.open.push(Slot { id, socket: handle, waiting: Some(Instant::now()) });
        Some(id)
    }

    /// Marks connection `id` as waiting for a request (`true`) or being
    /// answered; `false` when it was closed for another.
    pub(super) fn mark(&self, id: u64, waiting: bool) -> bool {
        let mut t = self.lock();
        let Some(slot) = t.open.iter_mut().find(|s| s.id == id) else { return false };
        slot.waiting = waiting.then(Instant::now);
        true
    }

    pub(super) fn leave(&self, id: u64) {
        self.lock().open.retain(|s| s.id != id);
    }

    /// Counts a new event stream in, if there is room.
    pub(super) fn start_stream(&self) -> bool {
        let mut t = self.lock();
        let room = t.streams < MAX_STREAMS;
        t.streams += usize::from(room);
        room
    }

    pub(super) fn end_stream(&self) {
        let mut t = self.lock();
        t.streams = t.streams.saturating_sub(1);
    }

    pub(super) fn close_all(&self) {
        let mut t = self.lock();
        t.closed = true;
        for s in t.open.drain(..) {
            let _ = s.socket.shutdown(Shutdown::Both);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;
    use std::net::TcpListener;
    use std::time::Duration;

    /// `n` connections on a local listener: (client ends, server ends).
    fn pairs(n: usize) -> (Vec<TcpStream>, Vec<TcpStream>) {
        let listener = TcpListener::bind("127.0.0.1:0").expect("a local listener");
        let addr = listener.local_addr().expect("its address");
        let clients: Vec<TcpStream> =
            (0..n).map(|_| TcpStream::connect(addr).expect("a connection")).collect();
        let servers = (0..n).map(|_| listener.accept().expect("an accepted connection").0).collect();
        (clients, servers)
    }

    #[test]
    fn a_full_table_closes_the_connection_waiting_longest_or_refuses() {
        let (clients, servers) = pairs(MAX_CONNECTIONS + 2);
        let conns = Conns::default();
        let ids: Vec<u64> =
            servers[..MAX_CONNECTIONS].iter().map(|s| conns.admit(s).expect("room")).collect();
        for &id in &ids {
            assert!(conns.mark(id, false));
        }
        // Only connection 5 waits for a request: it gives way.
        assert!(conns.mark(ids[5], true));
        let newcomer = conns.admit(&servers[MAX_CONNECTIONS]).expect("room made");
        assert!(!conns.mark(ids[5], true), "connection 5 was closed");
        let mut byte = [0u8; 1];
        clients[5].set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        assert_eq!(
            (&clients[5]).read(&mut byte).expect("the end of the stream"),
            0,
            "its client sees the end"
        );
        // With every connection being answered, a newcomer is refused.
        assert!(conns.mark(newcomer, false));
        assert_eq!(conns.admit(&servers[MAX_CONNECTIONS + 1]), None);
        conns.leave(ids[0]);
        assert!(conns.admit(&servers[MAX_CONNECTIONS + 1]).is_some(), "a slot left is taken");
    }

    #[test]
    fn event_streams_are_capped() {
        let conns = Conns::default();
        assert!((0..MAX_STREAMS).all(|_| conns.start_stream()));
        assert!(!conns.start_stream());
        conns.end_stream();
        assert!(conns.start_stream());
    }
}
