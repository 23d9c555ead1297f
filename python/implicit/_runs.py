"""Shared plumbing of the one-call runners: the tool's experiment code, its JSON as a dict."""
import json


def call(fn, settings, seed, out, threads):
    """Runs an experiment of the command-line tool and returns its JSON result as a dict.

    The settings, seed, out and threads are passed as given: the compiled side checks each
    against the range of the tool's flag and names the keyword it refuses."""
    return json.loads(fn(settings, seed, out, threads))
