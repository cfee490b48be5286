//! A Foxglove WebSocket client for the live view's tests and benchmark:
//! connects with the `foxglove.sdk.v1` subprotocol, reads the advertised
//! channels, subscribes, and collects message data. It decodes nothing
//! with slipfront's own types: messages are decoded with the schemas the
//! server advertises (prost-reflect).

#![allow(dead_code)]

use base64::Engine as _;
use prost_reflect::{DescriptorPool, DynamicMessage, MessageDescriptor};
use std::collections::{BTreeMap, HashMap};
use std::net::TcpStream;
use std::time::{Duration, Instant};
use tungstenite::client::IntoClientRequest;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

/// A channel as the server advertised it.
#[derive(Debug, Clone)]
pub struct Advertised {
    pub id: u64,
    pub topic: String,
    pub encoding: String,
    pub schema_name: String,
    pub schema_encoding: String,
    /// The schema, decoded from base64.
    pub schema: Vec<u8>,
}

impl Advertised {
    /// The message type the schema describes.
    pub fn descriptor(&self) -> MessageDescriptor {
        assert_eq!(self.schema_encoding, "protobuf", "{}", self.topic);
        let pool = DescriptorPool::decode(&self.schema[..])
            .unwrap_or_else(|e| panic!("{}: schema is not a FileDescriptorSet: {e}", self.topic));
        pool.get_message_by_name(&self.schema_name)
            .unwrap_or_else(|| panic!("{}: schema lacks {}", self.topic, self.schema_name))
    }
}

/// One message received.
#[derive(Debug, Clone)]
pub struct Received {
    pub topic: String,
    pub log_time: u64,
    pub data: Vec<u8>,
}

pub enum Event {
    Message(Received),
    /// The server's clock (Time capability), ns.
    Time(u64),
    /// Any other text message (status and the like).
    Text(serde_json::Value),
    /// The server closed the connection (a close frame or end of stream).
    Closed,
    /// Nothing came within the read timeout.
    Idle,
}

pub struct LiveClient {
    socket: WebSocket<MaybeTlsStream<TcpStream>>,
    pub channels: HashMap<u64, Advertised>,
    /// Subscription id → topic.
    subscriptions: HashMap<u32, String>,
    pub server_info: Option<serde_json::Value>,
}

impl LiveClient {
    pub fn connect(url: &str) -> LiveClient {
        let mut request = url.into_client_request().expect("a ws:// URL");
        request
            .headers_mut()
            .insert("Sec-WebSocket-Protocol", "foxglove.sdk.v1".parse().unwrap());
        let (socket, response) =
            tungstenite::connect(request).unwrap_or_else(|e| panic!("connect {url}: {e}"));
        assert_eq!(
            response
                .headers()
                .get("sec-websocket-protocol")
                .map(|v| v.to_str().unwrap()),
            Some("foxglove.sdk.v1")
        );
        let mut client = LiveClient {
            socket,
            channels: HashMap::new(),
            subscriptions: HashMap::new(),
            server_info: None,
        };
        client.set_read_timeout(Duration::from_millis(200));
        client
    }

    pub fn set_read_timeout(&mut self, timeout: Duration) {
        if let MaybeTlsStream::Plain(s) = self.socket.get_mut() {
            s.set_read_timeout(Some(timeout)).unwrap();
        }
    }

    /// Reads until every topic in `topics` is advertised.
    pub fn wait_for_channels(&mut self, topics: &[&str], timeout: Duration) {
        let started = Instant::now();
        while !topics
            .iter()
            .all(|t| self.channels.values().any(|c| c.topic == *t))
        {
            assert!(
                started.elapsed() < timeout,
                "not advertised within {timeout:?}: {topics:?}; have {:?}",
                self.channels.values().map(|c| &c.topic).collect::<Vec<_>>()
            );
            if let Event::Closed = self.next() {
                panic!("closed before advertising {topics:?}");
            }
        }
    }

    pub fn channel(&self, topic: &str) -> &Advertised {
        self.channels
            .values()
            .find(|c| c.topic == topic)
            .unwrap_or_else(|| panic!("{topic} is not advertised"))
    }

    /// Subscribes to `topics` in one message.
    pub fn subscribe(&mut self, topics: &[&str]) {
        let mut subscriptions = Vec::new();
        for topic in topics {
            let id = self.subscriptions.len() as u32 + 1;
            let channel = self.channel(topic).id;
            self.subscriptions.insert(id, topic.to_string());
            subscriptions.push(serde_json::json!({"id": id, "channelId": channel}));
        }
        let text = serde_json::json!({"op": "subscribe", "subscriptions": subscriptions});
        self.socket
            .send(Message::Text(text.to_string().into()))
            .expect("send subscribe");
    }

    /// The next event from the server.
    pub fn next(&mut self) -> Event {
        let message = match self.socket.read() {
            Ok(m) => m,
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                return Event::Idle
            }
            Err(_) => return Event::Closed,
        };
        match message {
            Message::Text(text) => {
                let v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
                match v["op"].as_str() {
                    Some("advertise") => {
                        for c in v["channels"].as_array().expect("channels") {
                            let s = |k: &str| c[k].as_str().unwrap_or_default().to_string();
                            let schema = base64::engine::general_purpose::STANDARD
                                .decode(s("schema"))
                                .expect("base64 schema");
                            let a = Advertised {
                                id: c["id"].as_u64().expect("id"),
                                topic: s("topic"),
                                encoding: s("encoding"),
                                schema_name: s("schemaName"),
                                schema_encoding: s("schemaEncoding"),
                                schema,
                            };
                            self.channels.insert(a.id, a);
                        }
                        self.next()
                    }
                    Some("serverInfo") => {
                        self.server_info = Some(v);
                        self.next()
                    }
                    _ => Event::Text(v),
                }
            }
            Message::Binary(b) => match b.first() {
                Some(1) => {
                    let id = u32::from_le_bytes(b[1..5].try_into().unwrap());
                    let log_time = u64::from_le_bytes(b[5..13].try_into().unwrap());
                    Event::Message(Received {
                        topic: self.subscriptions[&id].clone(),
                        log_time,
                        data: b[13..].to_vec(),
                    })
                }
                Some(2) => Event::Time(u64::from_le_bytes(b[1..9].try_into().unwrap())),
                _ => self.next(),
            },
            Message::Close(_) => Event::Closed,
            _ => self.next(),
        }
    }

    /// Every message until the server closes (or `timeout` passes), by
    /// topic in arrival order; and the server times seen.
    pub fn collect_until_closed(
        &mut self,
        timeout: Duration,
    ) -> (BTreeMap<String, Vec<Received>>, Vec<u64>) {
        let started = Instant::now();
        let mut by_topic: BTreeMap<String, Vec<Received>> = BTreeMap::new();
        let mut times = Vec::new();
        loop {
            assert!(
                started.elapsed() < timeout,
                "the server did not close within {timeout:?}"
            );
            match self.next() {
                Event::Message(m) => by_topic.entry(m.topic.clone()).or_default().push(m),
                Event::Time(t) => times.push(t),
                Event::Closed => return (by_topic, times),
                Event::Text(_) | Event::Idle => {}
            }
        }
    }
}

/// Decodes `data` as the message `descriptor` describes.
pub fn decode(descriptor: &MessageDescriptor, data: &[u8]) -> DynamicMessage {
    DynamicMessage::decode(descriptor.clone(), data)
        .unwrap_or_else(|e| panic!("{} does not decode: {e}", descriptor.full_name()))
}
