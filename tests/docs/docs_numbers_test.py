#!/usr/bin/env python3
"""The `numbers` check of docs_check.py on small docs written here: it passes a doc whose numbers
are what its command gives, and fails each way a number can drift (run by ctest as
docs_numbers_check_itself)."""
import contextlib
import io
import pathlib
import sys
import tempfile
import types
import unittest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import docs_check  # noqa: E402


def doc_with(comment_claims, text, command=None):
    command = command or (f"{sys.executable} -c "
                          "'print(\"{\\\"rate\\\": 0.85, \\\"rmse\\\": {\\\"mean\\\": 0.30349}, "
                          "\\\"runs\\\": [3, 4]}\")'")
    return f"# A doc\n\n<!-- numbers: {command}\n{comment_claims}\n-->\n{text}\n"


def check(doc_text):
    """(exit code, printed text) of `numbers --at doc.md:3` on the doc."""
    with tempfile.TemporaryDirectory() as folder:
        root = pathlib.Path(folder)
        (root / "doc.md").write_text(doc_text, encoding="utf-8")
        args = types.SimpleNamespace(root=str(root), cli="", timeout=60.0, list=False,
                                     at="doc.md:3", docs=[])
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            code = docs_check.numbers(args)
        return code, out.getvalue()


class NumbersCheck(unittest.TestCase):
    def test_numbers_the_command_gives_pass(self):
        code, out = check(doc_with("rate 0.85\nrmse.mean 0.303\nruns[1] 4",
                                   "It succeeded at a rate of 0.85 with RMSE 0.303 in 4 runs."))
        self.assertEqual(code, 0, out)

    def test_a_number_the_command_no_longer_gives_fails(self):
        code, out = check(doc_with("rate 0.75", "It succeeded at a rate of 0.75."))
        self.assertEqual(code, 1)
        self.assertIn("the doc says rate = 0.75", out)

    def test_rounding_is_to_the_digits_written(self):
        self.assertEqual(check(doc_with("rmse.mean 0.3035", "RMSE 0.3035."))[0], 0)
        self.assertEqual(check(doc_with("rmse.mean 0.30", "RMSE 0.30."))[0], 0)
        self.assertEqual(check(doc_with("rmse.mean 0.304", "RMSE 0.304."))[0], 1)

    def test_a_text_that_drifted_from_its_comment_fails(self):
        code, out = check(doc_with("rate 0.85", "It succeeded at a rate of 0.86."))
        self.assertEqual(code, 1)
        self.assertIn("does not state 0.85", out)
        # 0.85 inside another number is not the number.
        self.assertEqual(check(doc_with("rate 0.85", "A rate of 10.857."))[0], 1)
        # Only the paragraph below the comment speaks for it.
        self.assertEqual(check(doc_with("rate 0.85", "A rate of 0.86.\n\nLater, 0.85."))[0], 1)

    def test_in_a_table_the_row_that_quotes_the_command_states_its_numbers(self):
        fake = f"{sys.executable} -c 'print(\"{{\\\"rate\\\": 0.85}}\")'"
        table = ("| method | rate | command |\n|---|---|---|\n"
                 "| a | 0.85 | `other` |\n| b | 0.86 | `" + fake + "` |")
        code, out = check(doc_with("rate 0.85", table, fake + " --json"))
        self.assertEqual(code, 1, out)
        self.assertIn("does not state 0.85", out)
        table = table.replace("0.86", "0.85 [0.8, 0.9]")
        self.assertEqual(check(doc_with("rate 0.85", table, fake + " --json"))[0], 0)

    def test_a_key_the_command_does_not_give_fails(self):
        code, out = check(doc_with("rate_b 0.85", "A rate of 0.85."))
        self.assertEqual(code, 1)
        self.assertIn("gives no number 'rate_b'", out)

    def test_a_command_without_json_or_exit_0_fails(self):
        code, out = check(doc_with("rate 0.85", "A rate of 0.85.", f"{sys.executable} -c 'print(1'"))
        self.assertEqual(code, 1)
        self.assertIn("exited with 1", out)
        code, out = check(doc_with("rate 0.85", "A rate of 0.85.", "echo rate 0.85"))
        self.assertEqual(code, 1)
        self.assertIn("printed no JSON", out)

    def test_a_malformed_comment_fails(self):
        code, out = check(doc_with("rate about 0.85", "A rate of 0.85."))
        self.assertEqual(code, 1)
        self.assertIn("expected 'KEY NUMBER'", out)

    def test_a_comment_in_a_code_block_is_an_example_not_a_check(self):
        with tempfile.TemporaryDirectory() as folder:
            root = pathlib.Path(folder)
            (root / "doc.md").write_text("```markdown\n" + doc_with("rate 0.9", "0.8") + "```\n",
                                         encoding="utf-8")
            args = types.SimpleNamespace(root=str(root), list=True, docs=[str(root / "doc.md")])
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                docs_check.numbers(args)
            self.assertEqual(out.getvalue(), "")

    def test_the_list_names_every_comment_and_its_speed(self):
        with tempfile.TemporaryDirectory() as folder:
            root = pathlib.Path(folder)
            (root / "doc.md").write_text(
                doc_with("rate 0.85", "0.85") + "\n<!-- numbers slow: echo {}\nx 1\n-->\n1\n",
                encoding="utf-8")
            args = types.SimpleNamespace(root=str(root), list=True, docs=[str(root / "doc.md")])
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                docs_check.numbers(args)
            self.assertEqual(out.getvalue().split(), ["doc.md:3|fast", "doc.md:8|slow"])


if __name__ == "__main__":
    unittest.main()
