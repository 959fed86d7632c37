//! A network you can set: a TCP relay on loopback that carries each byte to a server
//! after a chosen round trip and at a chosen bandwidth, both ways, so that a walk over
//! HTTP meets the latency and the bandwidth of a real link on one machine.
//!
//! Each direction is one link shared by every connection through the relay, as an access
//! link is: a chunk leaves when the link is free (its bytes take `8·len / bandwidth` to
//! send) and arrives half a round trip later. Nothing is dropped or reordered; TCP's own
//! slow start is not modelled (loopback has none to speak of), so a real link of the
//! same figures is somewhat slower on the first bytes of a connection.
//!
//! It listens on 127.0.0.1 only and forwards to one upstream address.
//!
//! ```no_run
//! use std::time::Duration;
//! use flaneur_bench::link::{Link, LinkSpec};
//!
//! let upstream = "127.0.0.1:8080".parse().unwrap();
//! let link = Link::start(upstream, LinkSpec { rtt: Duration::from_millis(50), mbit: Some(20.0) })
//!     .unwrap();
//! println!("the server, 50 ms away: http://{}/city.flaneur", link.addr());
//! ```

use std::io::{self, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The link's figures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkSpec {
    /// The round trip: each direction delays its bytes by half of it.
    pub rtt: Duration,
    /// Each direction's bandwidth, megabits per second; `None` for no limit.
    pub mbit: Option<f64>,
}

/// A running relay; dropped, it stops accepting and ends its connections' threads as
/// their peers close.
pub struct Link {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    shared: Arc<Shared>,
    accept: Option<JoinHandle<()>>,
}

/// What every connection of one relay shares: the two directions' links and the counts.
struct Shared {
    spec: LinkSpec,
    /// When each direction's link is next free to send: to the server, to the client.
    up: Mutex<Instant>,
    down: Mutex<Instant>,
    bytes_up: AtomicU64,
    bytes_down: AtomicU64,
    connections: AtomicU64,
}

/// The longest piece the relay reads and sends at once: small enough that the bandwidth
/// is paced finely (16 KiB take 6.5 ms at 20 Mbit/s).
const CHUNK: usize = 16 * 1024;

impl Link {
    /// Starts a relay on a free loopback port to `upstream`.
    pub fn start(upstream: SocketAddr, spec: LinkSpec) -> io::Result<Link> {
        if spec.mbit.is_some_and(|m| !(m.is_finite() && m > 0.0)) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                format!(
                    "a link's bandwidth must be above 0 Mbit/s, not {:?}",
                    spec.mbit
                ),
            ));
        }
        let listener = TcpListener::bind(("127.0.0.1", 0))?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let stop = Arc::new(AtomicBool::new(false));
        let now = Instant::now();
        let shared = Arc::new(Shared {
            spec,
            up: Mutex::new(now),
            down: Mutex::new(now),
            bytes_up: AtomicU64::new(0),
            bytes_down: AtomicU64::new(0),
            connections: AtomicU64::new(0),
        });
        let accept = {
            let (stop, shared) = (stop.clone(), shared.clone());
            std::thread::Builder::new()
                .name("link-accept".into())
                .spawn(move || accept_loop(listener, upstream, &stop, &shared))?
        };
        Ok(Link {
            addr,
            stop,
            shared,
            accept: Some(accept),
        })
    }

    /// Where clients connect.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The link's figures.
    pub fn spec(&self) -> LinkSpec {
        self.shared.spec
    }

    /// Bytes carried to the server and back to the clients so far.
    pub fn bytes(&self) -> (u64, u64) {
        (
            self.shared.bytes_up.load(Ordering::Relaxed),
            self.shared.bytes_down.load(Ordering::Relaxed),
        )
    }

    /// Connections accepted so far.
    pub fn connections(&self) -> u64 {
        self.shared.connections.load(Ordering::Relaxed)
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.accept.take() {
            let _ = h.join();
        }
    }
}

fn accept_loop(
    listener: TcpListener,
    upstream: SocketAddr,
    stop: &AtomicBool,
    shared: &Arc<Shared>,
) {
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((client, _)) => {
                shared.connections.fetch_add(1, Ordering::Relaxed);
                let shared = shared.clone();
                // A connection the upstream refuses is closed at once, as a real
                // link to a server that is down would be after its round trip.
                let _ = std::thread::Builder::new()
                    .name("link-conn".into())
                    .spawn(move || {
                        if let Ok(server) = TcpStream::connect(upstream) {
                            relay(client, server, &shared);
                        }
                    });
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_millis(2));
            }
            Err(_) => std::thread::sleep(Duration::from_millis(2)),
        }
    }
}

/// Carries one connection both ways until both sides have closed.
fn relay(client: TcpStream, server: TcpStream, shared: &Arc<Shared>) {
    let _ = client.set_nodelay(true);
    let _ = server.set_nodelay(true);
    let (Ok(client2), Ok(server2)) = (client.try_clone(), server.try_clone()) else {
        return;
    };
    let up = {
        let shared = shared.clone();
        std::thread::spawn(move || pump(client, server2, &shared, Direction::Up))
    };
    pump(server, client2, shared, Direction::Down);
    let _ = up.join();
}

#[derive(Clone, Copy)]
enum Direction {
    Up,
    Down,
}

/// Reads `from` and writes to `to` what it read, each chunk when the link delivers it:
/// a reader thread stamps chunks as they come, this one sends them on time.
fn pump(from: TcpStream, mut to: TcpStream, shared: &Arc<Shared>, dir: Direction) {
    let (tx, rx) = mpsc::channel::<(Instant, Vec<u8>)>();
    let reader = {
        let shared = shared.clone();
        let mut from2 = match from.try_clone() {
            Ok(f) => f,
            Err(_) => return,
        };
        std::thread::spawn(move || {
            let mut buf = vec![0u8; CHUNK];
            loop {
                match from2.read(&mut buf) {
                    Ok(0) | Err(_) => break,
                    Ok(n) => {
                        let due = shared.schedule(dir, n);
                        if tx.send((due, buf[..n].to_vec())).is_err() {
                            break;
                        }
                    }
                }
            }
        })
    };
    for (due, bytes) in rx {
        let wait = due.saturating_duration_since(Instant::now());
        if !wait.is_zero() {
            std::thread::sleep(wait);
        }
        // Counted before it is written, so that a peer that has read it all sees it counted.
        let counter = match dir {
            Direction::Up => &shared.bytes_up,
            Direction::Down => &shared.bytes_down,
        };
        counter.fetch_add(bytes.len() as u64, Ordering::Relaxed);
        if to.write_all(&bytes).is_err() {
            break;
        }
    }
    // The sender closed (or the receiver did): pass the close on.
    let _ = to.shutdown(Shutdown::Write);
    let _ = from.shutdown(Shutdown::Read);
    let _ = reader.join();
}

impl Shared {
    /// When `len` bytes read now in direction `dir` reach the other side.
    fn schedule(&self, dir: Direction, len: usize) -> Instant {
        let now = Instant::now();
        let send = match self.spec.mbit {
            Some(mbit) => Duration::from_secs_f64(len as f64 * 8.0 / (mbit * 1e6)),
            None => Duration::ZERO,
        };
        let link = match dir {
            Direction::Up => &self.up,
            Direction::Down => &self.down,
        };
        let leaves = {
            let mut free = link.lock().unwrap_or_else(|p| p.into_inner());
            let start = (*free).max(now);
            *free = start + send;
            start + send
        };
        leaves + self.spec.rtt / 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A server that answers each line it reads with `reply` bytes.
    fn echo_server(reply: usize) -> SocketAddr {
        let listener = TcpListener::bind(("127.0.0.1", 0)).unwrap();
        let addr = listener.local_addr().unwrap();
        std::thread::spawn(move || {
            for conn in listener.incoming() {
                let Ok(mut conn) = conn else { break };
                std::thread::spawn(move || {
                    let mut byte = [0u8; 1];
                    while conn.read_exact(&mut byte).is_ok() {
                        if byte[0] == b'\n' && conn.write_all(&vec![7u8; reply]).is_err() {
                            break;
                        }
                    }
                });
            }
        });
        addr
    }

    fn ask(conn: &mut TcpStream, reply: usize) -> Duration {
        let t = Instant::now();
        conn.write_all(b"\n").unwrap();
        let mut got = vec![0u8; reply];
        conn.read_exact(&mut got).unwrap();
        assert!(got.iter().all(|b| *b == 7));
        t.elapsed()
    }

    #[test]
    fn a_small_exchange_takes_one_round_trip() {
        let server = echo_server(10);
        let link = Link::start(
            server,
            LinkSpec {
                rtt: Duration::from_millis(60),
                mbit: None,
            },
        )
        .unwrap();
        let mut conn = TcpStream::connect(link.addr()).unwrap();
        conn.set_nodelay(true).unwrap();
        for _ in 0..3 {
            let took = ask(&mut conn, 10);
            // Never sooner than the round trip; later only by scheduling.
            assert!(took >= Duration::from_millis(60), "{took:?}");
            assert!(took < Duration::from_millis(60 + 500), "{took:?}");
        }
        assert_eq!(link.bytes(), (3, 30));
        assert_eq!(link.connections(), 1);
    }

    #[test]
    fn a_large_answer_takes_its_bytes_over_the_bandwidth() {
        let reply = 500_000;
        let server = echo_server(reply);
        let link = Link::start(
            server,
            LinkSpec {
                rtt: Duration::ZERO,
                mbit: Some(40.0),
            },
        )
        .unwrap();
        let mut conn = TcpStream::connect(link.addr()).unwrap();
        let took = ask(&mut conn, reply);
        // 4 Mbit at 40 Mbit/s: 100 ms at least.
        assert!(took >= Duration::from_millis(95), "{took:?}");
        assert_eq!(link.bytes().1, reply as u64);
    }

    #[test]
    fn a_bandwidth_of_zero_is_refused() {
        let spec = LinkSpec {
            rtt: Duration::ZERO,
            mbit: Some(0.0),
        };
        let err = Link::start("127.0.0.1:9".parse().unwrap(), spec)
            .err()
            .unwrap();
        assert!(err.to_string().contains("bandwidth"), "{err}");
    }
}
