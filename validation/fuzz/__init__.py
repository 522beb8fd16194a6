"""Fuzz harness of issue 23: malformed, absurd, tiny, faulty and concurrent inputs to every
``tiltbench`` command, each run as a subprocess and classified.

Run: ``python -m validation.fuzz --out DIR --seed 0 [--jobs 2] [--kinds a,b] [--src PATH]``.
It builds its inputs in ``DIR/base`` (generated sets, edited copies), runs every case in its
own folder ``DIR/cases/<id>``, prints a table by kind and writes ``DIR/fuzz.json``.

The cases are written from the issue text and the user docs (``docs/*.md``,
``tiltbench X --help``), not from the code that handles them.

The front door (issue 31: the log readers and every command that reads a log, the sensor
profile) has kinds of its own, in :mod:`validation.fuzz.front_door` with the log writers of
:mod:`validation.fuzz.logfiles`: ``unit_mistake``, ``sensor_file``, ``bad_bag``,
``cell_count``, ``unit_suffix``, ``log_refusal`` and the named valid set ``valid_log``
(``--kinds unit_mistake,sensor_file,bad_bag,cell_count,unit_suffix,log_refusal,valid_log``;
``tests/test_fuzz_front_door.py`` runs them in its process).

Classification of one run (a case can carry several faults)
-----------------------------------------------------------
=================  ===========================================================================
``traceback``      stderr holds ``Traceback``
``last_resort``    stderr holds a last-resort message: ``please report``, ``would be nan``,
                   ``Singular matrix``, ``OverflowError``
``multi_line``     an error exit (2, or undocumented) whose error is not one message: one line
                   and its continuation lines (wrapped at 100 columns, indented 4 spaces);
                   ``note:``, ``warning:`` and ``[progress]`` lines and theirs aside
``wide_line``      a line on stderr (or readable stdout: not a JSON object) wider than 100
                   columns, unless it is a single token (a path or URL longer than that)
``hang``           still running after the timeout (60 s): killed with its process group
``leftover``       a hidden file (``.name``, not a ``*.lock``) beside a target that was not
                   there before the run (after a killed run: after the *next* run too)
``result_lost``    two writers of one path both exit 0 without ``--force``, or an input
                   file changed by the run (``--save`` onto its own input)
``bad_exit``       an exit code outside the documented ones (0; 2 for bad input; 1 only
                   for ``validate``'s "fail")
``silent_wrong``   exit 0 with an answer the truth contradicts beyond the reported
                   uncertainty (fused / dead-reckoned end > 5σ from the true end, with no
                   "inconsistent" in the output), or exit 0 on an input the issue says must
                   be refused (an edited calibration graded, |ρ| > 1, n = 0)
``vague``          a refusal (exit 2) whose error line does not say what the case says it
                   must (``Case.says``): the likely unit, the file and field, the line
``refused_valid``  exit 2 on an input of the named valid set (``expect="valid"``)
=================  ===========================================================================

A case with none of these is ``clean``. The summary ends with the widest line printed (of
every case; of the refused ones) and the widest single word (a path may be wider than 100).
The harness imports neither ``bench`` nor ``calib`` (it judges the command line from
outside, as a user would).
"""
