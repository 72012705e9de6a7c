#!/usr/bin/env python3
"""Decode every message of an appell MCAP overlay with the PyPI readers Foxglove's users have,
outside the Rust code: python3 scripts/checks/overlay_decode.py FILE.mcap [FILE.mcap ...].

Each message is read with `mcap` (the official Python reader) and decoded against its channel's
schema: protobuf through the FileDescriptorSet the file carries (`mcap-protobuf-support`'s
decoder, which builds the message classes from it with `protobuf`), JSON by `json` and then
validated against the channel's JSON Schema (`jsonschema`). Prints one line per topic (schema,
messages decoded) and exits 1 on the first message that does not decode or validate, 2 when a
package is missing. Not run by CI (.ci/run): it needs the network for its packages, so
docs/overlay.md says how to run it by hand:

    python3 -m venv /tmp/venv-overlay
    /tmp/venv-overlay/bin/pip install mcap mcap-protobuf-support jsonschema
    /tmp/venv-overlay/bin/python scripts/checks/overlay_decode.py fit.mcap
"""
import json
import sys
from collections import Counter

try:
    import jsonschema
    from mcap.reader import make_reader
    from mcap_protobuf.decoder import DecoderFactory
except ImportError as e:  # the packages above, in a venv
    print(f"missing package: {e.name} (pip install mcap mcap-protobuf-support jsonschema)", file=sys.stderr)
    sys.exit(2)


def unknown_fields(msg, prefix=""):
    """The paths of fields in `msg` (and the messages inside it) that its schema does not
    name: every byte of a message should be a field the schema knows."""
    from google.protobuf.descriptor import FieldDescriptor
    from google.protobuf.unknown_fields import UnknownFieldSet

    out = [f"{prefix}#{f.field_number}" for f in UnknownFieldSet(msg)]
    for field, value in msg.ListFields():
        if field.type != FieldDescriptor.TYPE_MESSAGE:
            continue
        items = value if field.is_repeated else [value]
        for i, item in enumerate(items):
            out += unknown_fields(item, f"{prefix}{field.name}[{i}].")
    return out


def check(path):
    """Decode every message of one file; returns {topic: (schema, encoding, count)}."""
    protobuf = DecoderFactory()
    decoders = {}
    validators = {}
    counts = Counter()
    kinds = {}
    with open(path, "rb") as f:
        reader = make_reader(f)
        for schema, channel, message in reader.iter_messages(log_time_order=True):
            if schema is None:
                raise SystemExit(f"{path}: {channel.topic}: a channel without a schema")
            where = f"{path}: {channel.topic} at log time {message.log_time}"
            if channel.message_encoding == "protobuf":
                if schema.encoding != "protobuf":
                    raise SystemExit(f"{where}: protobuf messages with a {schema.encoding!r} schema")
                decode = decoders.get(schema.id)
                if decode is None:
                    decode = protobuf.decoder_for(channel.message_encoding, schema)
                    decoders[schema.id] = decode
                msg = decode(message.data)
                unknown = unknown_fields(msg)
                if unknown:
                    raise SystemExit(f"{where}: {schema.name}: fields the schema does not name: {unknown}")
            elif channel.message_encoding == "json":
                if schema.encoding != "jsonschema":
                    raise SystemExit(f"{where}: JSON messages with a {schema.encoding!r} schema")
                validator = validators.get(schema.id)
                if validator is None:
                    doc = json.loads(schema.data)
                    jsonschema.Draft202012Validator.check_schema(doc)
                    validator = jsonschema.Draft202012Validator(doc)
                    validators[schema.id] = validator
                value = json.loads(message.data)
                errors = sorted(validator.iter_errors(value), key=str)
                if errors:
                    raise SystemExit(f"{where}: {schema.name}: {errors[0].message}")
                # A key the schema does not list would be read by nothing that follows it.
                props = json.loads(schema.data).get("properties", {})
                extra = [k for k in value if k not in props] if isinstance(value, dict) else []
                if extra:
                    raise SystemExit(f"{where}: {schema.name}: keys {extra} not in the schema")
            else:
                raise SystemExit(f"{where}: message encoding {channel.message_encoding!r}")
            counts[channel.topic] += 1
            kinds[channel.topic] = (schema.name, channel.message_encoding)
    return {t: (*kinds[t], counts[t]) for t in sorted(counts)}


def main():
    if len(sys.argv) < 2:
        print(__doc__.split("\n\n")[0], file=sys.stderr)
        sys.exit(2)
    for path in sys.argv[1:]:
        topics = check(path)
        total = sum(c for _, _, c in topics.values())
        print(f"{path}: {total} messages on {len(topics)} topics, every one decoded")
        for topic, (schema, enc, n) in topics.items():
            print(f"  {topic:<20} {schema:<22} {enc:<9} {n}")


if __name__ == "__main__":
    main()
