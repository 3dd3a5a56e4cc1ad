//! crash-scene: Scene files (TOML), validation with precise locations, mesh generators and importers.
pub mod error;
pub mod spans;

#[cfg(test)]
mod scratch {
    #[test]
    fn show() {
        #[derive(serde::Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct B { name: String, t: f64, #[serde(default)] fix: Vec<F> }
        #[derive(serde::Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct F { dofs: toml::Value }
        #[derive(serde::Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct S { end_time: f64, bodies: Vec<B> }
        let docs = [
            "end_time = 1\n[[bodies]]\nname = 'a'\nt = 1\n[[bodies]]\nname = 'b'\nt = 1\nfoo = 3\n",
            "end_time = 1\n[[bodies]]\nname = 'a'\nt = 1\n[[bodies]]\nname = 'b'\n",
            "end_time = 1\n[[bodies]]\nname = 'a'\nt = 'x'\n",
            "end_time = 1\n[[bodies]]\nname = 'a'\nt = 1\n[[bodies.fix]]\nfoo=1\n",
            "end_time = 1\nbodies = [ {name='a', t=2, q=3} ]\n",
            "end_time = 1\n[[bodies]]\nname = 'a'\nt = 1 2\n",
        ];
        for d in docs {
            let idx = crate::spans::SpanIndex::new(d);
            println!("{idx:?}");
            let e = toml::from_str::<S>(d).unwrap_err();
            let sp = e.span();
            println!("msg={:?} span={:?} text={:?} path={:?}", e.message(), sp, sp.clone().map(|s| &d[s]), e.span().and_then(|s| idx.path_at(s.start).map(String::from)));
        }
    }
}
