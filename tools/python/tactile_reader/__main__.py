"""python3 -m tactile_reader LOG: one line per record (time, topic, kind, summary)."""

import sys

from . import LogReader


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        print("usage: python3 -m tactile_reader LOG   (prints one line per record)")
        return 0 if len(argv) == 2 else 2
    try:
        reader = LogReader(argv[1])
    except (OSError, ValueError) as e:
        print(f"tactile_reader: {e}", file=sys.stderr)
        return 1
    with reader:
        for rec in reader:
            m = rec.decode()
            what = "undecodable" if m is None else m.kind
            extra = ""
            if m is not None and m.kind == "tactile_frame":
                contact = sum(1 for e in m.body.elements if e.contact)
                extra = f" seq {m.body.sequence} contact {contact}/{len(m.body.elements)}"
            elif m is not None and m.kind == "event":
                extra = " " + m.body.DESCRIPTOR.fields_by_name["kind"].enum_type.values_by_number[m.body.kind].name
            print(f"{rec.receive_time_ns} {rec.topic} {what}{extra}")
        if reader.status != "end":
            print(f"tactile_reader: {reader.problem}", file=sys.stderr)
            return 0 if reader.status == "truncated" else 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
