//! `Push.words`: parameters that the frame and the families declare word by word in their
//! `layout.in.rs` (`push_words!`), each a typed [`Word`] const on this side and a
//! `push_<name>()` getter in GLSL. The frame fills its own words and calls each family's
//! `push_words` hook once a frame (`registry::Family`); every pass pushes the same words.

use std::marker::PhantomData;

/// How many words the push block holds (its `words` array).
pub const COUNT: usize = 14;

/// One word of `Push.words`, of the type its shaders read it as (`u32`: `uint`, `f32`:
/// `float`, by its bits).
#[derive(Clone, Copy, Debug)]
pub struct Word<T> {
    index: usize,
    _ty: PhantomData<T>,
}

impl<T> Word<T> {
    pub const fn at(index: usize) -> Word<T> {
        Word { index, _ty: PhantomData }
    }
    pub fn index(self) -> usize {
        self.index
    }
}

/// A value a word can hold.
pub trait WordValue: Copy {
    fn bits(self) -> u32;
}

impl WordValue for u32 {
    fn bits(self) -> u32 {
        self
    }
}

impl WordValue for f32 {
    fn bits(self) -> u32 {
        self.to_bits()
    }
}

/// The words of one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PushWords(pub [u32; COUNT]);

impl PushWords {
    pub fn set<T: WordValue>(&mut self, word: Word<T>, value: T) {
        self.0[word.index] = value.bits();
    }
    pub fn get(&self, word: Word<u32>) -> u32 {
        self.0[word.index]
    }
}
