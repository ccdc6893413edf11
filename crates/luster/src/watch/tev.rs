//! `--tev HOST:PORT`: every pass of the render streamed to the tev image
//! viewer (<https://github.com/Tom94/tev>) over its TCP protocol, as pbrt's
//! `--display-server` does, through the `tev_client` crate.
//!
//! Each frame's size gets a `CreateImage` (channels R, G, B) when it differs
//! from the last one's (the preview, then the full image), and every pass an
//! `UpdateImage` with the whole film: the film's linear values, as an `.exr`
//! output holds them (a course scene's 0–255 range: lower tev's exposure by
//! 8 stops). The image is named after the camera's `ImageName`. A viewer
//! that goes away ends the stream with one warning; the render goes on.

use luster_render::film::Film;
use std::net::{TcpStream, ToSocketAddrs};
use std::time::Duration;
use tev_client::{PacketCreateImage, PacketUpdateImage, TevClient};

/// How long connecting to the viewer may take.
const CONNECT: Duration = Duration::from_secs(5);

const CHANNELS: [&str; 3] = ["R", "G", "B"];

/// A connection to tev.
pub struct Tev {
    client: Option<TevClient>,
    addr: String,
    /// Name and size of the image last created in the viewer.
    created: Option<(String, u32, u32)>,
}

impl Tev {
    /// Connects to tev listening at `addr` (`HOST:PORT`); the error is one sentence.
    pub fn connect(addr: &str) -> Result<Tev, String> {
        let fail = |why: String| format!("cannot reach the tev viewer at {addr}: {why}");
        let targets = addr.to_socket_addrs().map_err(|e| fail(e.to_string()))?;
        let mut last = String::from("the name has no address");
        for a in targets {
            match TcpStream::connect_timeout(&a, CONNECT) {
                Ok(s) => {
                    let _ = s.set_nodelay(true);
                    let client = Some(TevClient::wrap(s));
                    return Ok(Tev { client, addr: addr.to_string(), created: None });
                }
                Err(e) => last = e.to_string(),
            }
        }
        Err(fail(last))
    }

    /// Shows `film` in the viewer as image `name`. A failed send warns once
    /// and ends the stream.
    pub fn show(&mut self, name: &str, film: &Film) {
        let Some(client) = self.client.as_mut() else { return };
        if film.width == 0 || film.height == 0 {
            return;
        }
        // tev's strings end at a NUL.
        let name = name.replace('\0', "");
        let mut sent = Ok(());
        if self.created.as_ref() != Some(&(name.clone(), film.width, film.height)) {
            sent = client.send(PacketCreateImage {
                image_name: &name,
                grab_focus: true,
                width: film.width,
                height: film.height,
                channel_names: &CHANNELS,
            });
            self.created = Some((name.clone(), film.width, film.height));
        }
        if sent.is_ok() {
            let data: Vec<f32> = film.pixels.iter().flat_map(|p| p.to_array()).collect();
            sent = client.send(PacketUpdateImage {
                image_name: &name,
                grab_focus: false,
                channel_names: &CHANNELS,
                channel_offsets: &[0, 1, 2],
                channel_strides: &[3, 3, 3],
                x: 0,
                y: 0,
                width: film.width,
                height: film.height,
                data: &data,
            });
        }
        if let Err(e) = sent {
            eprintln!(
                "warning: the tev viewer at {} stopped answering ({e}); no more frames go to it",
                self.addr
            );
            self.client = None;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use luster_core::math::Vec3;
    use std::io::Read;

    /// The packets a fake viewer received: (type, body after the type byte).
    fn packets(bytes: &[u8]) -> Vec<(u8, Vec<u8>)> {
        let mut out = Vec::new();
        let mut at = 0;
        while at + 5 <= bytes.len() {
            let len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
            out.push((bytes[at + 4], bytes[at + 5..at + len].to_vec()));
            at += len;
        }
        assert_eq!(at, bytes.len(), "a packet was cut short");
        out
    }

    /// Reads a NUL-terminated string or a little-endian u32 off the front of `b`.
    fn string(b: &mut &[u8]) -> String {
        let end = b.iter().position(|&c| c == 0).expect("a terminated string");
        let s = String::from_utf8(b[..end].to_vec()).unwrap();
        *b = &b[end + 1..];
        s
    }
    fn word(b: &mut &[u8]) -> u32 {
        let w = u32::from_le_bytes(b[..4].try_into().unwrap());
        *b = &b[4..];
        w
    }

    #[test]
    fn frames_become_create_and_update_packets() {
        let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let viewer = std::thread::spawn(move || {
            let (mut s, _) = listener.accept().unwrap();
            let mut all = Vec::new();
            s.read_to_end(&mut all).unwrap();
            all
        });
        let mut tev = Tev::connect(&addr).unwrap();
        let mut film = Film::new(3, 2);
        film.pixels[4] = Vec3::new(1.0, 2.0, 3.0);
        tev.show("out.png", &film);
        tev.show("out.png", &film);
        let small = Film::new(1, 1);
        tev.show("out.png", &small);
        drop(tev);
        let got = packets(&viewer.join().unwrap());
        let kinds: Vec<u8> = got.iter().map(|p| p.0).collect();
        // Create, update, update (same size), create at the new size, update.
        assert_eq!(kinds, [4, 6, 6, 4, 6]);
        let mut b = &got[0].1[..];
        assert_eq!(b[0], 1, "the new image takes the focus");
        b = &b[1..];
        assert_eq!(string(&mut b), "out.png");
        assert_eq!((word(&mut b), word(&mut b), word(&mut b)), (3, 2, 3));
        assert_eq!([string(&mut b), string(&mut b), string(&mut b)], ["R", "G", "B"]);
        let mut b = &got[1].1[1..];
        assert_eq!(string(&mut b), "out.png");
        assert_eq!(word(&mut b), 3);
        for c in ["R", "G", "B"] {
            assert_eq!(string(&mut b), c);
        }
        assert_eq!([word(&mut b), word(&mut b), word(&mut b), word(&mut b)], [0, 0, 3, 2]);
        // Offsets and strides (u64 each), then the interleaved floats.
        b = &b[6 * 8..];
        let floats: Vec<f32> = b.chunks(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
        assert_eq!(floats.len(), 3 * 2 * 3);
        assert_eq!(&floats[12..15], &[1.0, 2.0, 3.0], "pixel 4 is (1, 0) of the second row");
        let mut b = &got[3].1[1..];
        string(&mut b);
        assert_eq!((word(&mut b), word(&mut b)), (1, 1));
    }

    #[test]
    fn an_absent_viewer_is_one_sentence() {
        // A port just freed: nothing listens there.
        let addr = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().to_string();
        let e = Tev::connect(&addr).err().expect("no viewer");
        assert!(e.starts_with(&format!("cannot reach the tev viewer at {addr}: ")), "{e}");
        assert!(Tev::connect("no port here").is_err());
    }
}
