"""Copies an MCAP file with its chunks compressed, as other tools write bags (issue 19: `twin map`
and `--replay` read compressed bags). Uses the MCAP project's own Python writer, so the chunks,
their CRCs and the summary are what other tools produce, not what the twin's reader expects.

    python3 recompress_mcap.py IN.mcap OUT.mcap zstd|lz4
"""

import sys

from mcap.reader import make_reader
from mcap.writer import CompressionType, Writer


def main() -> None:
    source, target, kind = sys.argv[1], sys.argv[2], sys.argv[3]
    compression = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4}[kind]
    with open(source, "rb") as f, open(target, "wb") as out:
        reader = make_reader(f)
        writer = Writer(out, compression=compression, chunk_size=64 * 1024)
        writer.start(profile="ros2", library="recompress_mcap.py")
        schemas, channels = {}, {}
        for schema, channel, message in reader.iter_messages():
            if schema is not None and schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(
                    schema.name, schema.encoding, schema.data
                )
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(
                    channel.topic,
                    channel.message_encoding,
                    schemas.get(channel.schema_id, 0),
                    channel.metadata,
                )
            writer.add_message(
                channels[channel.id],
                message.log_time,
                message.data,
                message.publish_time,
                message.sequence,
            )
        writer.finish()


if __name__ == "__main__":
    main()
