"""Gold-ruby glass (seed example 1): gold nanospheres (p = 0.0005) in silica.

Writes the composite's n, k against silica (the seed's Figure 1), plate transmission,
colour swatches under D65 and A, gold-rod variants and the Kramers–Kronig check.

    python examples/ema_gold_ruby.py [output_dir]
"""

import sys

from nmmm.demo.gold_ruby import gold_ruby_demo

if __name__ == "__main__":
    result = gold_ruby_demo(sys.argv[1] if len(sys.argv) > 1 else "ema_gold_ruby_output")
    print(result["title"])
    print(result["text"])
    for path in result["figures"]:
        print("figure:", path)
