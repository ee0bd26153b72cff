#!/usr/bin/env python3
"""Writes the store inputs of the fuzz harnesses (standard library only):

  seeds/store_record/*.txt     stored records of format 2 for the trial hash "fuzz" (the hash
                               fuzz_store_record.cpp reads them under), as store_record writes them
  seeds/store_file/*.sqlite    a small result store (page size 512) holding such records
  regression/store_record/     records that must be refused: one metric value too many, a
                               garbage value (both sealed with the right checksum, so that it is
                               the shape or the value that is caught), a wrong checksum
  regression/store_file/       files that are not stores or are damaged: text, the seed store
                               with garbage over its table's pages, a `trials` table of another
                               shape, a store holding a record with one metric value too many

Run from anywhere: python3 tests/fuzz/make_store_inputs.py
"""
import hashlib
import os
import sqlite3

HERE = os.path.dirname(os.path.abspath(__file__))
HASH = "fuzz"

APPROXIMATION = ("fill_distance separation_distance gram_condition_number gram_min_eigenvalue "
                 "gram_max_eigenvalue power_function_sup power_function_floor l2_error sup_error "
                 "error_floor interpolant_native_norm").split()


def body(names, fields):
    lines = ["rkhs-record 2", " ".join(["metric_names"] + names), "rkhs-trial 1"] + fields
    return "\n".join(lines) + "\n"


def sealed(text, for_hash=HASH):
    return text + "checksum " + hashlib.sha256((for_hash + "\n" + text).encode()).hexdigest() + "\n"


def approximation_fields(metrics):
    return ["ok 1", "reason ", "solve cholesky", "flags ", "seconds 0.0123", "data ",
            "metrics " + metrics, "samples ", "road "]


GOOD_METRICS = "0.39269908169872414 0.39269908169872414 12.5 0.08 1 0.25 1e-16 0.03125 0.0625 " \
               "1e-15 1.4142135623730951"

RECORDS = {
    "approximation.txt": body(APPROXIMATION, approximation_fields(GOOD_METRICS)),
    "failed.txt": body(["gram_condition_number", "power_function_sup"],
                       ["ok 0", "reason Gram matrix singular to working precision\\nat n = 80",
                        "solve pseudo_inverse", "flags gram_condition_number;power_function_sup",
                        "seconds 2.5e-05", "data ", "metrics inf nan", "samples ", "road "]),
    "adaptive.txt": body(["l2_error", "final_state_error", "steps"],
                         ["ok 1", "reason ", "solve cholesky", "engine lap_map",
                          "flags ", "seconds 1.75",
                          "data sha256:0f1e2d3c4b5a69788796a5b4c3d2e1f00f1e2d3c4b5a69788796a5b4c3d2e1f0",
                          "metrics 0.0123 4.5e-07 1200",
                          "samples 0 0 0 1.5 0.25 0.125 3 2e-300 -0",
                          "road 0 0.5 1 0.5",
                          "snapshot 1 0.1 0.2 0.3 0.4",
                          "snapshot 10 0.5 0.25 0.125 5e-324"]),
}


def write(path, text):
    with open(path, "w", newline="\n") as out:
        out.write(text)


def main():
    seeds = os.path.join(HERE, "seeds", "store_record")
    for name, text in RECORDS.items():
        write(os.path.join(seeds, name), sealed(text))

    regression = os.path.join(HERE, "regression", "store_record")
    approximation = RECORDS["approximation.txt"]
    write(os.path.join(regression, "one_metric_too_many.txt"),
          sealed(approximation.replace("\nmetrics ", "\nmetrics 0.5 ")))
    write(os.path.join(regression, "garbage_metric_value.txt"),
          sealed(approximation.replace("\nmetrics 0.39269908169872414", "\nmetrics 0.3926x9908")))
    write(os.path.join(regression, "checksum_of_another_trial.txt"), sealed(approximation, "other"))

    store = os.path.join(HERE, "seeds", "store_file", "store.sqlite")
    records = [(name, text) for name, text in sorted(RECORDS.items())]
    write_store(store, records)

    files = os.path.join(HERE, "regression", "store_file")
    write(os.path.join(files, "not_a_database.txt"), "rkhs-record 2\nmetric_names\n")
    with open(store, "rb") as f:
        pages = bytearray(f.read())
    pages[1024:] = b"\x5a" * (len(pages) - 1024)  # the table's b-tree pages (page size 512)
    with open(os.path.join(files, "damaged_pages.sqlite"), "wb") as f:
        f.write(pages)
    other = os.path.join(files, "other_schema.sqlite")
    write_store(other, [], "CREATE TABLE trials (hash INTEGER, result BLOB)")
    db = sqlite3.connect(other)
    db.execute("INSERT INTO trials VALUES (1, x'00ff')")
    db.commit()
    db.close()
    write_store(os.path.join(files, "one_metric_too_many.sqlite"),
                [("one_metric_too_many", approximation.replace("\nmetrics ", "\nmetrics 0.5 "))])


def write_store(path, records, schema=None):
    """A store of `records` (key, record body) sealed for the hashes 00fuzz, 01fuzz, ..."""
    if os.path.exists(path):
        os.remove(path)
    db = sqlite3.connect(path)
    db.execute("PRAGMA page_size = 512")
    db.execute(schema or "CREATE TABLE IF NOT EXISTS trials (hash TEXT PRIMARY KEY, study TEXT "
               "NOT NULL, key TEXT NOT NULL, result TEXT NOT NULL, stored TEXT NOT NULL)")
    for i, (name, text) in enumerate(records):
        trial = f"{i:02d}{HASH}"
        db.execute("INSERT INTO trials VALUES (?, ?, ?, ?, ?)",
                   (trial, "fuzz", name, sealed(text, trial), "2024-01-01 00:00:00"))
    db.commit()
    db.execute("VACUUM")
    db.close()


if __name__ == "__main__":
    main()
