"""Shared plumbing of the one-call runners: the tool's experiment code, its JSON as a dict."""
import json


def call(fn, settings, seed, out, threads):
    """Runs an experiment of the command-line tool and returns its JSON result as a dict."""
    return json.loads(fn(settings, int(seed), "" if out is None else str(out), int(threads)))
