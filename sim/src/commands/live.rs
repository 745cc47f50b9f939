//! A live view: the run's ROS 2 topics published over the Foxglove WebSocket protocol
//! (`foxglove.websocket.v1`) on 127.0.0.1, so Foxglove (open connection → Foxglove WebSocket →
//! `ws://127.0.0.1:PORT`) shows the robot as it moves.
//!
//! The server announces its channels (`advertise`, CDR messages with `ros2msg` schemas, the same
//! as `run.mcap`'s), streams each published message to the clients subscribed to its channel
//! (binary opcode 1: subscription id, timestamp, CDR payload), and keeps the last message of a
//! latched topic (`/tf_static`) for clients that subscribe later. Each client has a bounded
//! queue: when a client does not read, its queue fills and further messages for it are dropped
//! and counted — the run never waits for a viewer and memory stays bounded.

use robot::Stamp;
use robot::logs::ros2::Encoded;
use std::collections::{BTreeMap, HashMap};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TrySendError, sync_channel};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;
use tungstenite::Message;

/// The WebSocket subprotocol spoken.
pub const SUBPROTOCOL: &str = "foxglove.websocket.v1";

/// Messages a client's queue holds before further ones are dropped for it.
pub const CLIENT_QUEUE: usize = 512;

/// Topics whose last message a client gets when it subscribes.
const LATCHED: [&str; 1] = ["/tf_static"];

/// One advertised channel.
#[derive(Clone, Debug)]
struct Channel {
    id: u32,
    topic: String,
    schema_name: &'static str,
    schema: String,
}

impl Channel {
    fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "id": self.id,
            "topic": self.topic,
            "encoding": "cdr",
            "schemaName": self.schema_name,
            "schema": self.schema,
            "schemaEncoding": "ros2msg",
        })
    }
}

/// What the publisher hands a client's thread.
enum Outgoing {
    /// A JSON text message (an `advertise`).
    Text(String),
    /// A message on a channel: the client sends it if subscribed.
    Data {
        channel: u32,
        at: Stamp,
        payload: Arc<Vec<u8>>,
    },
}

/// A message's stamp and payload.
type Stamped = (Stamp, Arc<Vec<u8>>);

#[derive(Default)]
struct Shared {
    channels: Mutex<Vec<Channel>>,
    /// The last message of each latched channel.
    latched: Mutex<BTreeMap<u32, Stamped>>,
    clients: Mutex<Vec<SyncSender<Outgoing>>>,
    stop: AtomicBool,
    dropped: AtomicU64,
    sent: AtomicU64,
    subscriptions: AtomicU64,
}

/// A Foxglove WebSocket server publishing ROS 2 messages.
pub struct LiveServer {
    addr: SocketAddr,
    shared: Arc<Shared>,
    threads: Arc<Mutex<Vec<JoinHandle<()>>>>,
    accept: Option<JoinHandle<()>>,
}

/// Why the live server cannot start.
#[derive(Debug, thiserror::Error)]
#[error("live view on {addr}: {source}")]
pub struct LiveError {
    /// The address asked for.
    pub addr: String,
    /// Why.
    #[source]
    pub source: std::io::Error,
}

impl LiveServer {
    /// Listens on `addr` (`127.0.0.1:0` picks a free port; see [`LiveServer::addr`]).
    pub fn start(addr: &str) -> Result<Self, LiveError> {
        let error = |source| LiveError {
            addr: addr.to_string(),
            source,
        };
        let listener = TcpListener::bind(addr).map_err(error)?;
        listener.set_nonblocking(true).map_err(error)?;
        let local = listener.local_addr().map_err(error)?;
        let shared = Arc::new(Shared::default());
        let threads = Arc::new(Mutex::new(Vec::new()));
        let accept = {
            let (shared, threads) = (shared.clone(), threads.clone());
            std::thread::spawn(move || accept_loop(&listener, &shared, &threads))
        };
        Ok(LiveServer {
            addr: local,
            shared,
            threads,
            accept: Some(accept),
        })
    }

    /// The address it listens on.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Announces `topic` carrying messages like `example` (clients connected later get it with
    /// the others on connection). Publishing announces a topic too; announcing first lets a
    /// client subscribe before the first message.
    pub fn advertise(&self, topic: &str, example: &Encoded) -> u32 {
        let mut channels = self.shared.channels.lock().expect("not poisoned");
        if let Some(c) = channels.iter().find(|c| c.topic == topic) {
            return c.id;
        }
        let channel = Channel {
            id: channels.len() as u32 + 1,
            topic: topic.to_string(),
            schema_name: example.name,
            schema: (example.definition)(),
        };
        let text = serde_json::json!({"op": "advertise", "channels": [channel.json()]}).to_string();
        let id = channel.id;
        channels.push(channel);
        drop(channels);
        self.broadcast(|| Outgoing::Text(text.clone()));
        id
    }

    /// Publishes `msg` on `topic`, stamped `at`, to every client subscribed to it.
    pub fn publish(&self, topic: &str, at: Stamp, msg: &Encoded) {
        let channel = self.advertise(topic, msg);
        let latched = LATCHED.contains(&topic);
        if !latched && self.shared.clients.lock().expect("not poisoned").is_empty() {
            return; // nobody to send it to: no copy
        }
        let payload = Arc::new(msg.cdr.clone());
        if latched {
            self.shared
                .latched
                .lock()
                .expect("not poisoned")
                .insert(channel, (at, payload.clone()));
        }
        self.broadcast(|| Outgoing::Data {
            channel,
            at,
            payload: payload.clone(),
        });
    }

    fn broadcast(&self, message: impl Fn() -> Outgoing) {
        let mut clients = self.shared.clients.lock().expect("not poisoned");
        clients.retain(|tx| match tx.try_send(message()) {
            Ok(()) => true,
            Err(TrySendError::Full(_)) => {
                self.shared.dropped.fetch_add(1, Ordering::Relaxed);
                true
            }
            Err(TrySendError::Disconnected(_)) => false,
        });
    }

    /// Messages dropped because a client's queue was full.
    pub fn dropped(&self) -> u64 {
        self.shared.dropped.load(Ordering::Relaxed)
    }

    /// Messages sent to clients.
    pub fn sent(&self) -> u64 {
        self.shared.sent.load(Ordering::Relaxed)
    }

    /// Subscriptions clients have made so far.
    pub fn subscriptions(&self) -> u64 {
        self.shared.subscriptions.load(Ordering::SeqCst)
    }

    /// Sends what the clients' queues hold, closes their connections and stops.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.shared.stop.store(true, Ordering::SeqCst);
        if let Some(accept) = self.accept.take() {
            let _ = accept.join();
        }
        let threads = std::mem::take(&mut *self.threads.lock().expect("not poisoned"));
        for t in threads {
            let _ = t.join();
        }
    }
}

impl std::fmt::Debug for LiveServer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "LiveServer({})", self.addr)
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        self.shutdown();
    }
}

fn accept_loop(listener: &TcpListener, shared: &Arc<Shared>, threads: &Mutex<Vec<JoinHandle<()>>>) {
    while !shared.stop.load(Ordering::SeqCst) {
        match listener.accept() {
            Ok((stream, _)) => {
                let (tx, rx) = sync_channel(CLIENT_QUEUE);
                let shared = shared.clone();
                // Registered before the handshake, so no message published meanwhile is missed.
                shared.clients.lock().expect("not poisoned").push(tx);
                let thread = std::thread::spawn(move || {
                    let _ = serve_client(stream, &shared, &rx);
                });
                threads.lock().expect("not poisoned").push(thread);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(Duration::from_millis(5));
            }
            Err(_) => std::thread::sleep(Duration::from_millis(5)),
        }
    }
}

/// One client: the handshake (choosing the Foxglove subprotocol), `serverInfo` and the channels,
/// then subscriptions in and messages out until the server stops or the client leaves.
fn serve_client(
    stream: TcpStream,
    shared: &Shared,
    rx: &Receiver<Outgoing>,
) -> Result<(), tungstenite::Error> {
    use tungstenite::handshake::server::{ErrorResponse, Request, Response};
    stream.set_nonblocking(false)?;
    stream.set_read_timeout(Some(Duration::from_secs(5)))?;
    let choose = |request: &Request, mut response: Response| -> Result<Response, ErrorResponse> {
        let offered = request
            .headers()
            .get_all("Sec-WebSocket-Protocol")
            .iter()
            .filter_map(|v| v.to_str().ok())
            .any(|v| v.split(',').any(|p| p.trim() == SUBPROTOCOL));
        if offered {
            response.headers_mut().insert(
                "Sec-WebSocket-Protocol",
                SUBPROTOCOL.parse().expect("a valid header value"),
            );
        }
        Ok(response)
    };
    let mut ws = tungstenite::accept_hdr(stream, choose).map_err(|e| match e {
        tungstenite::HandshakeError::Failure(e) => e,
        tungstenite::HandshakeError::Interrupted(_) => tungstenite::Error::ConnectionClosed,
    })?;
    ws.get_mut()
        .set_read_timeout(Some(Duration::from_millis(10)))?;
    // A client that stops reading is let go after this, rather than holding the server.
    ws.get_mut()
        .set_write_timeout(Some(Duration::from_secs(2)))?;
    ws.send(Message::text(
        serde_json::json!({
            "op": "serverInfo",
            "name": "robot twin",
            "capabilities": [],
            "metadata": {},
        })
        .to_string(),
    ))?;
    let channels: Vec<serde_json::Value> = shared
        .channels
        .lock()
        .expect("not poisoned")
        .iter()
        .map(Channel::json)
        .collect();
    if !channels.is_empty() {
        ws.send(Message::text(
            serde_json::json!({"op": "advertise", "channels": channels}).to_string(),
        ))?;
    }
    // Channel → subscription id.
    let mut subscriptions: HashMap<u32, u32> = HashMap::new();
    loop {
        match ws.read() {
            Ok(Message::Text(text)) => {
                for (channel, id) in subscribe(text.as_str(), &mut subscriptions) {
                    shared.subscriptions.fetch_add(1, Ordering::SeqCst);
                    let latched = shared
                        .latched
                        .lock()
                        .expect("not poisoned")
                        .get(&channel)
                        .cloned();
                    if let Some((at, payload)) = latched {
                        ws.send(data_frame(id, at, &payload))?;
                    }
                }
            }
            Ok(Message::Close(_)) => return Ok(()),
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(e) => return Err(e),
        }
        let stopping = shared.stop.load(Ordering::SeqCst);
        while let Ok(out) = rx.try_recv() {
            match out {
                Outgoing::Text(text) => ws.send(Message::text(text))?,
                Outgoing::Data {
                    channel,
                    at,
                    payload,
                } => {
                    if let Some(&id) = subscriptions.get(&channel) {
                        ws.send(data_frame(id, at, &payload))?;
                        shared.sent.fetch_add(1, Ordering::Relaxed);
                    }
                }
            }
        }
        if stopping {
            let _ = ws.close(None);
            let _ = ws.flush();
            return Ok(());
        }
    }
}

/// Applies a client's `subscribe` or `unsubscribe`; returns the new (channel, subscription).
fn subscribe(text: &str, subscriptions: &mut HashMap<u32, u32>) -> Vec<(u32, u32)> {
    let Ok(value) = serde_json::from_str::<serde_json::Value>(text) else {
        return Vec::new();
    };
    let number = |v: &serde_json::Value| v.as_u64().and_then(|n| u32::try_from(n).ok());
    match value["op"].as_str() {
        Some("subscribe") => value["subscriptions"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|s| Some((number(&s["channelId"])?, number(&s["id"])?)))
            .inspect(|&(channel, id)| {
                subscriptions.insert(channel, id);
            })
            .collect(),
        Some("unsubscribe") => {
            let ids: Vec<u32> = value["subscriptionIds"]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(number)
                .collect();
            subscriptions.retain(|_, id| !ids.contains(id));
            Vec::new()
        }
        _ => Vec::new(),
    }
}

/// Binary opcode 1: subscription id, receive time (ns), payload, little-endian.
fn data_frame(subscription: u32, at: Stamp, payload: &[u8]) -> Message {
    let mut frame = Vec::with_capacity(13 + payload.len());
    frame.push(1);
    frame.extend_from_slice(&subscription.to_le_bytes());
    frame.extend_from_slice(&at.0.to_le_bytes());
    frame.extend_from_slice(payload);
    Message::binary(frame)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn client(
        addr: SocketAddr,
    ) -> tungstenite::WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>> {
        use tungstenite::client::IntoClientRequest;
        let mut request = format!("ws://{addr}").into_client_request().unwrap();
        request
            .headers_mut()
            .insert("Sec-WebSocket-Protocol", SUBPROTOCOL.parse().unwrap());
        let (ws, response) = tungstenite::connect(request).unwrap();
        assert_eq!(
            response.headers()["Sec-WebSocket-Protocol"],
            SUBPROTOCOL,
            "the server chose Foxglove's subprotocol"
        );
        ws
    }

    fn example(len: usize) -> Encoded {
        Encoded {
            name: "rosgraph_msgs/msg/Clock",
            definition: || "builtin_interfaces/Time clock\n".to_string(),
            cdr: vec![0; len],
        }
    }

    /// A client that subscribes and then never reads costs the server a bounded queue: publishing
    /// never waits for it, the overflow is dropped and counted, and stopping lets it go.
    #[test]
    fn a_client_that_never_reads_is_bounded_and_let_go() {
        let server = LiveServer::start("127.0.0.1:0").unwrap();
        let channel = server.advertise("/big", &example(8));
        let mut ws = client(server.addr());
        let info = ws.read().unwrap();
        assert!(info.to_text().unwrap().contains("serverInfo"), "{info:?}");
        ws.send(Message::text(
            serde_json::json!({"op": "subscribe", "subscriptions": [{"id": 3, "channelId": channel}]})
                .to_string(),
        ))
        .unwrap();
        while server.subscriptions() == 0 {
            std::thread::sleep(Duration::from_millis(2));
        }
        let payload = example(16 * 1024);
        for k in 0..4000 {
            server.publish("/big", Stamp(k), &payload);
        }
        assert!(server.dropped() > 0, "a full queue drops");
        assert!(server.sent() < 4000);
        server.stop();
        drop(ws);
    }

    #[test]
    fn subscriptions_follow_subscribe_and_unsubscribe() {
        let mut subs = HashMap::new();
        let new = subscribe(
            r#"{"op":"subscribe","subscriptions":[{"id":1,"channelId":4},{"id":2,"channelId":5}]}"#,
            &mut subs,
        );
        assert_eq!(new, vec![(4, 1), (5, 2)]);
        subscribe(r#"{"op":"unsubscribe","subscriptionIds":[1]}"#, &mut subs);
        assert_eq!(subs.into_iter().collect::<Vec<_>>(), vec![(5, 2)]);
        assert!(subscribe("not json", &mut HashMap::new()).is_empty());
    }
}
