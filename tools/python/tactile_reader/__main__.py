"""python3 -m tactile_reader: one line per message (time, topic, kind, summary), from a log file
or from live publishers."""

import argparse
import signal
import sys
import time

from ._deps import MissingDependency

PROG = "python3 -m tactile_reader"
DEFAULT_SILENCE_TIMEOUT_S = 5.0


def _parser():
    p = argparse.ArgumentParser(
        prog=PROG,
        description="Prints one line per message (receive time in ns, topic, kind, summary) of a "
        "tactile_record log, or of live publishers with --subscribe. Library use and the log "
        "format: docs/tools.md#tactile_reader-python, docs/recording.md.",
        epilog="Exit status: 0 done (a log cut short is read up to its last whole frame and "
        "reported), 1 a bad or corrupt file, a missing Python module, or nothing heard within "
        "--silence-timeout, 2 a usage error.",
    )
    p.add_argument("log", nargs="?", metavar="LOG", help="a tactile_record log (.tlog)")
    p.add_argument("--subscribe", action="append", default=[], metavar="ENDPOINT",
                   help="read live from this publisher instead of a log, e.g. tcp://127.0.0.1:5555 "
                   "(repeatable)")
    p.add_argument("--topic", action="append", metavar="PREFIX",
                   help="topic prefix to subscribe to (repeatable; default: frame/ stats/ event "
                   "truth; \"\" for everything)")
    p.add_argument("--silence-timeout", type=float, default=DEFAULT_SILENCE_TIMEOUT_S, metavar="S",
                   help="with --subscribe: exit 1, naming the endpoints, when nothing arrives for "
                   "S seconds (default %(default)s; 0 waits forever)")
    p.add_argument("--count", type=int, default=0, metavar="N",
                   help="with --subscribe: stop after N messages (default 0: until SIGINT/SIGTERM)")
    p.add_argument("--server-key", metavar="FILE.pub",
                   help="with --subscribe: the publishers' CURVE public key (docs/security.md)")
    p.add_argument("--client-key", metavar="FILE.key",
                   help="with --subscribe and --server-key: this subscriber's key pair (default: a "
                   "fresh one)")
    return p


def _line(m, receive_time_ns):
    extra = ""
    if m.kind == "tactile_frame":
        contact = sum(1 for e in m.body.elements if e.contact)
        extra = f" seq {m.body.sequence} contact {contact}/{len(m.body.elements)}"
    elif m.kind == "event":
        kinds = m.body.DESCRIPTOR.fields_by_name["kind"].enum_type.values_by_number
        extra = " " + (kinds[m.body.kind].name if m.body.kind in kinds else str(m.body.kind))
    elif m.kind == "decision":
        # hand_node's flags, each fingertip's slipping element ids and the detector that decided
        tips = " ".join(
            f.sensor_id + ("/SLIP[" + ",".join(str(i) for i in f.slipping_element_ids) + "]"
                           if f.slip else "")
            for f in m.body.fingertips)
        extra = f" {m.body.phase} {m.body.slip_detector or '-'} {tips}"
    return f"{receive_time_ns} {m.topic} {m.kind}{extra}"


def _read_log(path):
    from . import LogReader

    try:
        reader = LogReader(path)
    except (OSError, ValueError) as e:
        print(f"tactile_reader: {e}", file=sys.stderr)
        return 1
    with reader:
        for rec in reader:
            m = rec.message()
            if m is None:
                print(f"{rec.receive_time_ns} {rec.topic} undecodable")
            else:
                print(_line(m, rec.receive_time_ns))
        if reader.status != "end":
            print(f"tactile_reader: {reader.problem}", file=sys.stderr)
            return 0 if reader.status == "truncated" else 1
    return 0


def _subscribe(args):
    from . import Subscriber

    topics = args.topic if args.topic is not None else ["frame/", "stats/", "event", "truth"]
    endpoints = ", ".join(args.subscribe)
    try:
        sub = Subscriber(args.subscribe, topics=topics, server_key=args.server_key,
                         client_key=args.client_key)
    except (OSError, ValueError) as e:
        print(f"tactile_reader: {e}", file=sys.stderr)
        return 1
    except Exception as e:  # zmq.ZMQError: a malformed endpoint
        print(f"tactile_reader: cannot subscribe to {endpoints}: {e}", file=sys.stderr)
        return 1
    with sub:
        received = 0
        while args.count <= 0 or received < args.count:
            wait = args.silence_timeout if args.silence_timeout > 0 else 3600.0
            m = sub.receive(wait)
            if m is None:
                if args.silence_timeout <= 0:
                    continue
                after = f" (after {received} messages)" if received else ""
                print(f"tactile_reader: nothing heard from {endpoints} within "
                      f"{args.silence_timeout:g} s{after}", file=sys.stderr)
                return 1
            received += 1
            print(_line(m, time.time_ns()), flush=True)
    return 0


def main(argv):
    args = _parser().parse_args(argv[1:])  # usage errors: message and usage on stderr, exit 2
    if (args.log is None) == (not args.subscribe):
        _parser().error("give either LOG or --subscribe ENDPOINT")
    if args.client_key and not args.server_key:
        _parser().error("--client-key needs --server-key")
    if args.silence_timeout < 0:
        _parser().error(f"--silence-timeout {args.silence_timeout:g}: must be >= 0")
    # A reader closed early (| head) ends this process quietly, as it ends cat or grep.
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    try:
        return _read_log(args.log) if args.log is not None else _subscribe(args)
    except MissingDependency as e:
        print(f"tactile_reader: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
