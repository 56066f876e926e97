import json, sys
a = json.load(open(sys.argv[1])); b = json.load(open(sys.argv[2]))
keys = ["executed", "seal_agreement", "accuracy", "precision", "recall", "ap", "spearman"]
for name in ["basic", "typical", "adversarial"]:
    print(name, {k: (a["sets"][name].get(k), b["sets"][name].get(k)) for k in keys})
print("all", {k: (a["overall"].get(k), b["overall"].get(k)) for k in keys})
print(a["overall"]["lift_confusion"], b["overall"]["lift_confusion"])
print(a["overall"]["not_executed"], b["overall"]["not_executed"])
print(b["overall"]["lift_disagreements"])
ka = {(x["object"], x["seed"]): x for x in a["per_trial"]}
n = 0
for x in b["per_trial"]:
    y = ka[(x["object"], x["seed"])]
    if (x["success"], x["failure"]) != (y["success"], y["failure"]) or abs((x["label_rwr"] or 0) - (y["label_rwr"] or 0)) > 0.1:
        n += 1
        print(f'{x["object"]:28s} {x["seed"]:4d} sim {y["failure"]} -> {x["failure"]}  rwr {y["label_rwr"]} -> {x["label_rwr"]}')
print(n, "changed")
