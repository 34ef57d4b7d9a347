"""Decode a candump -L log with the project's DBC using cantools, print JSON.

Usage: cantools_decode.py <dbc> <log>. Prints one object per frame: id, message name and
every signal's physical value. Exits non-zero if any frame fails to decode.
"""
import json
import sys

import cantools


def frames(path):
    for line in open(path):
        _, _, frame = line.split()
        can_id, data = frame.split("##")
        # CAN FD candump: the first nibble after ## holds the flags (BRS, ESI).
        yield int(can_id, 16), bytes.fromhex(data[1:])


def main():
    db = cantools.database.load_file(sys.argv[1])
    out = []
    for can_id, data in frames(sys.argv[2]):
        message = db.get_message_by_frame_id(can_id)
        if not message.is_fd:
            raise SystemExit(f"{message.name} is not marked CAN FD in the DBC")
        signals = message.decode(data, decode_choices=False, scaling=True)
        out.append({"id": can_id, "name": message.name, "signals": signals})
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
