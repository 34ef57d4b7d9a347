"""Reads an MCAP file with the official Python reader and prints, as JSON, what a test checks:
every channel (topic, message encoding, schema name and encoding, message count), the
attachments' names, and every world -> torso transform of /tf with its log time.

usage: read_mcap.py FILE.mcap
"""

import json
import sys

from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory


def main(path):
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        counts = summary.statistics.channel_message_counts
        channels = []
        for channel_id, channel in summary.channels.items():
            schema = summary.schemas[channel.schema_id]
            channels.append(
                {
                    "topic": channel.topic,
                    "encoding": channel.message_encoding,
                    "schema": schema.name,
                    "schema_encoding": schema.encoding,
                    "count": counts.get(channel_id, 0),
                }
            )
        attachments = [a.name for a in reader.iter_attachments()]
        torso = []
        for _, _, message, decoded in reader.iter_decoded_messages(topics=["/tf"]):
            for t in decoded.transforms:
                if t.parent_frame_id == "world" and t.child_frame_id == "torso":
                    r, p = t.rotation, t.translation
                    torso.append(
                        {
                            "log_time_ns": message.log_time,
                            "xyz": [p.x, p.y, p.z],
                            "wxyz": [r.w, r.x, r.y, r.z],
                        }
                    )
        joints = None
        for _, _, _, decoded in reader.iter_decoded_messages(topics=["/joint_states"]):
            joints = list(decoded.name)
            break
    json.dump(
        {
            "channels": channels,
            "attachments": attachments,
            "torso": torso,
            "joint_names": joints,
        },
        sys.stdout,
    )


if __name__ == "__main__":
    main(sys.argv[1])
